"""Peer comparison in the same run: EXUDYN's eigenvalue computation against mbseig's (optional:
``pip install exudyn``, the ``bench`` extra).

Model: a 1-D chain of n unit masses between walls, springs k = 1000 with dashpots c = 0.5 in
parallel, plus one dashpot c₀ = 2 from the first mass to the wall: the damping is not
proportional, so each side takes its general path (EXUDYN ``ComputeODE2Eigenvalues`` with
``computeComplexEigenvalues=True``: M, K, D from its model, then the first-order system; mbseig:
linearization, then its dense general path).  Built the same in both: EXUDYN ``Node1D`` /
``Mass1D`` / ``CoordinateSpringDamper``, mbseig a case file with the same elements.

Accuracy of each side, against a reference independent of both: the backward error of each
computed eigenvalue alone (no eigenvector needed), η(s) = σ_min(s²M + sC + K) / (|s|²‖M‖ +
|s|‖C‖ + ‖K‖) (Tisseur 2000), from an SVD of the n × n matrix, for the ``n_check`` eigenvalues
of smallest |s| (the slow modes, whose relative accuracy a first-order form loses first); and
the largest distance between the two sides' eigenvalue sets, relative to |s|.

Spatial models (:func:`bench_peer_spatial`), rigid bodies under gravity hanging at rest in their
reference configuration (EXUDYN linearizes about its initial state, mbseig about its computed
equilibrium: the same point), each with a closed-form reference independent of both codes:

- ``spherical pendulum, damped pivot``: one rigid body (mass m, centre of mass l below the pivot,
  principal inertias Jx ≠ Jy ≠ Jz) on a spherical joint to the ground, with rotational dashpots
  cx ≠ cy ≠ cz at the pivot (non-proportional: the general path on both sides).  The swings about
  x and y and the spin about z decouple: (Jx + m l²)s² + cx s + m g l = 0, likewise with Jy, cy,
  and Jz s² + cz s = 0.
- ``spatial double pendulum``: the two links of ``cases/spatial_double_pendulum.toml`` (spherical
  joints at the pivot and between the links), undamped; the linearized compound double pendulum
  of that case's source gives two repeated pairs ±iω₁, ±iω₂ and two spins (s = 0, double each).

EXUDYN side: ``CreateRigidBody`` (Euler-parameter nodes, each with its normalization constraint),
node at the body's upper joint and the centre of mass offset (``RigidBodyInertia(com=...)``),
``gravity`` on the body, ``CreateSphericalJoint``, the pivot dashpots as
``CreateRigidBodySpringDamper`` (rotational damping only).  EXUDYN 1.13's
``ComputeODE2Eigenvalues`` takes M from its mass matrix, K and D from the Jacobian of the ODE2
right-hand side at the initial state, the constraint Jacobian C of all algebraic equations
(joints and Euler-parameter norms), a null-space basis of C from an SVD (singular values above
1e-12 count as constraints), and with ``computeComplexEigenvalues`` the eigenvalues of
−A⁻¹B, A = [[0, NᵀMN], [NᵀMN, 0]], B = [[NᵀKN, NᵀDN], [0, −NᵀMN]] (explicit inverse, LAPACK
geev).  Two terms of the linearization are missing from that K: the Jacobian of the loads (it
calls ``ComputeJacobianODE2RHS`` with ``computeLoadsJacobian = 0``, so gravity on an offset
centre of mass adds no stiffness: the pendulum swings come out at s = 0 or −c/I), and the
constraint-force stiffness Σλ∇²Φ (measured on the double pendulum: setting the initial
multipliers to the joint reactions, ``systemData.SetAECoordinates(..., configuration=Initial)``,
either sign, with analytic or numerical Jacobians, with or without
``jacobianConnectorDerivative``, leaves the projected K unchanged; its static solver, which
would supply them, stops on the double pendulum with a singular Jacobian, the free spins).  The
rows therefore run EXUDYN twice: its stock call once (its error recorded), and the same
sequence of EXUDYN calls with the load Jacobian switched on
(:func:`_exudyn_eigenvalues`, timed), which is exact for the single pendulum (its joint
constraint is linear in the node coordinates: λ∇²Φ = 0) and still misses Σλ∇²Φ on the double
pendulum (the joint between the links turns with the upper link).  mbseig: the case below
through ``linearize`` + ``modes``.  Accuracy of each side: the largest distance of its
eigenvalues from the closed-form set, relative to max(|s|, the smallest nonzero |s| of the
reference) (so that the rigid spins, s = 0, count on the same scale); the same over the
nonzero reference eigenvalues alone, relative to |s| (the spins are double roots, placed to
about √ε by any backward-stable solver); and η(s) of each side's eigenvalues on mbseig's
linearization (σ_min by SVD, as for the chain).
"""

from __future__ import annotations

import math
import tempfile
import warnings
from pathlib import Path

import numpy as np

from .peer_cases import double_case, pendulum_case
from .peer_chain import (
    chain_rows,
    eigenvalue_backward_error,
    exudyn_available,
    interleaved,
    linearized_modes,
)

__all__ = ["bench_peer", "bench_peer_spatial", "exudyn_available", "peer_lines"]


# ---------------------------------------------------------------------------------------------
# spatial models

SPATIAL_MIN_REPEATS = 11  # milliseconds per run: the medians take more runs than the chain's
SMALL_MIN_REPEATS = 51  # the small models stage by stage (a few ms a run)

PENDULUM = {"g": 9.81, "m": 2.0, "l": 0.8, "Jx": 0.02, "Jy": 0.03, "Jz": 0.01,
            "cx": 0.3, "cy": 0.5, "cz": 0.02}
DOUBLE = {"g": 9.81, "m1": 1.5, "m2": 0.9, "l1": 0.6, "c1": 0.25, "c2": 0.35, "J1": 0.04,
          "J2": 0.02, "Ja": 0.003}  # cases/spatial_double_pendulum.toml


def _pendulum_exact(p):
    """All six eigenvalues: the two swings (Jx + m l²)s² + cx s + m g l = 0 (and with y), the spin
    Jz s² + cz s = 0 (s = 0, −cz/Jz)."""
    s = []
    for J, c in ((p["Jx"], p["cx"]), (p["Jy"], p["cy"])):
        a, k = J + p["m"] * p["l"] ** 2, p["m"] * p["g"] * p["l"]
        d = np.sqrt(complex(c * c - 4 * a * k))
        s += [(-c + d) / (2 * a), (-c - d) / (2 * a)]
    return np.array(s + [0.0, -p["cz"] / p["Jz"]], complex)


def _double_exact(p):
    """All twelve eigenvalues: ±iω₁, ±iω₂ twice (two vertical planes), 0 four times (spins);
    ω² = (S ∓ √(S² − 4 D k₁k₂)) / (2D) (the case's source)."""
    g, m1, m2, l1, c1, c2 = (p[k] for k in ("g", "m1", "m2", "l1", "c1", "c2"))
    a = p["J1"] + m1 * c1**2 + m2 * l1**2
    b, d = m2 * l1 * c2, p["J2"] + m2 * c2**2
    k1, k2 = g * (m1 * c1 + m2 * l1), g * m2 * c2
    S, D = a * k2 + d * k1, a * d - b * b
    w = np.sqrt((S + np.array([-1.0, 1.0]) * np.sqrt(S * S - 4 * D * k1 * k2)) / (2 * D))
    return np.concatenate([1j * w, -1j * w, 1j * w, -1j * w, np.zeros(4)])


def _exudyn_spatial(name, p):
    import exudyn as exu
    from exudyn.utilities import RigidBodyInertia

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.CreateGround()
    grav = [0.0, 0.0, -p["g"]]
    ep = exu.NodeType.RotationEulerParameters

    def body(mass, J, com, at):
        inertia = RigidBodyInertia(mass=mass, inertiaTensor=np.diag(J), com=com,
                                   inertiaTensorAtCOM=True)
        return mbs.CreateRigidBody(referencePosition=at, inertia=inertia, gravity=grav, nodeType=ep)

    if name == "pendulum":
        bob = body(p["m"], [p["Jx"], p["Jy"], p["Jz"]], [0.0, 0.0, -p["l"]], [0.0, 0.0, 0.0])
        mbs.CreateSphericalJoint(itemNumbers=[ground, bob], position=[0.0, 0.0, 0.0])
        mbs.CreateRigidBodySpringDamper(itemNumbers=[ground, bob], localPosition0=[0.0, 0.0, 0.0],
                                        localPosition1=[0.0, 0.0, 0.0], stiffness=np.zeros((6, 6)),
                                        damping=np.diag([0.0, 0.0, 0.0, p["cx"], p["cy"], p["cz"]]))
    else:
        upper = body(p["m1"], [p["J1"], p["J1"], p["Ja"]], [0.0, 0.0, -p["c1"]], [0.0, 0.0, 0.0])
        lower = body(p["m2"], [p["J2"], p["J2"], p["Ja"]], [0.0, 0.0, -p["c2"]],
                     [0.0, 0.0, -p["l1"]])
        mbs.CreateSphericalJoint(itemNumbers=[ground, upper], position=[0.0, 0.0, 0.0])
        mbs.CreateSphericalJoint(itemNumbers=[upper, lower], position=[0.0, 0.0, -p["l1"]])
    mbs.Assemble()
    return SC, mbs


def _exudyn_eigenvalues(mbs, loads_jacobian=True, sv_tol=1e-12):
    """EXUDYN 1.13's ``ComputeODE2Eigenvalues(computeComplexEigenvalues=True,
    useAbsoluteValues=False)`` with constraints, step by step with the same EXUDYN calls, the
    load Jacobian of ``ComputeJacobianODE2RHS`` switched on where ``loads_jacobian`` (the stock
    call passes 0).  With ``loads_jacobian=False`` it is the stock computation (checked in
    tests/test_peer_spatial.py)."""
    import exudyn as exu
    from scipy.linalg import eig, svd

    ss = exu.SimulationSettings()
    ss.staticSolver.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.active = False
    S = exu.MainSolverStatic()
    S.InitializeSolver(mbs, ss)
    n2, n1 = S.GetODE2size(), S.GetODE1size()
    S.ComputeMassMatrix(mbs)
    M = np.array(S.GetSystemMassMatrix())[:n2, :n2]
    lj = 1 if loads_jacobian else 0
    S.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=-1, scalarFactor_ODE2_t=0, scalarFactor_ODE1=0,
                             computeLoadsJacobian=lj)
    S.ComputeJacobianAE(mbs, scalarFactor_ODE2=1.0, scalarFactor_ODE2_t=0.0, scalarFactor_ODE1=0.0,
                        velocityLevel=False)
    jac = np.array(S.GetSystemJacobian())
    K, C = jac[:n2, :n2], jac[:n2, n2 + n1:]
    S.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=0, scalarFactor_ODE2_t=-1, scalarFactor_ODE1=0,
                             computeLoadsJacobian=lj)
    D = np.array(S.GetSystemJacobian())[:n2, :n2]
    S.FinalizeSolver(mbs, ss)
    U, sv, _ = svd(C)
    N = U[:, int(np.sum(np.abs(sv) > sv_tol)):]
    Mn, Kn, Dn = (N.T @ X @ N for X in (M, K, D))
    k = Mn.shape[0]
    Z = np.zeros((k, k))
    A = np.block([[Z, Mn], [Mn, Z]])
    B = np.block([[Kn, Dn], [Z, -Mn]])
    return eig(-np.linalg.inv(A) @ B, right=False)


def _exudyn_stock(mbs):
    import exudyn as exu

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = exu.solver.ComputeODE2Eigenvalues(mbs, computeComplexEigenvalues=True,
                                               useAbsoluteValues=False)
    return np.asarray(ev[0], complex)


def _scaled_set_distance(a, b, scale):
    """max over a of min over b of |a − b| / max(|a|, scale), and the same from b (the larger)."""
    a, b = np.asarray(a, complex), np.asarray(b, complex)
    if not (a.size and b.size):
        return math.inf
    d1 = np.max(np.min(np.abs(a[:, None] - b[None, :]), axis=1) / np.maximum(np.abs(a), scale))
    d2 = np.max(np.min(np.abs(b[:, None] - a[None, :]), axis=1) / np.maximum(np.abs(b), scale))
    return float(max(d1, d2))


def _nearest_relative(ref, s):
    """max over the reference values of the distance to the nearest computed one, relative."""
    s = np.asarray(s, complex)
    if not s.size:
        return math.inf
    return float(np.max(np.min(np.abs(ref[:, None] - s[None, :]), axis=1) / np.abs(ref)))


SPATIAL_MODELS = {  # key: (label, parameters, case, exact)
    "pendulum": ("spherical pendulum, damped pivot", PENDULUM, pendulum_case, _pendulum_exact),
    "double": ("spatial double pendulum", DOUBLE, double_case, _double_exact),
}


def bench_peer(sizes, repeats, log, n_check=20):
    """Rows of the peer section (empty with a note when EXUDYN is not installed): the chain at
    each size (:func:`mbseig.bench.peer_chain.chain_rows`), then the spatial models
    (:func:`bench_peer_spatial`)."""
    from .pipeline_rows import bench_small_stages

    # mbseig's small models stage by stage against the eigen floor, with or without the peer
    small = bench_small_stages(max(repeats, SMALL_MIN_REPEATS), log)
    if not exudyn_available():
        log("peer: exudyn not installed (pip install exudyn): section skipped")
        return small, ("EXUDYN not installed (`pip install exudyn`, part of the `bench` extra): "
                       "not run")
    rows = small + chain_rows(sizes, repeats, log, n_check)
    rows += bench_peer_spatial(max(repeats, SPATIAL_MIN_REPEATS), log)[0]
    return rows, ""


def bench_peer_spatial(repeats, log, models=tuple(SPATIAL_MODELS)):
    """Rows of the spatial peer comparison (empty with a note when EXUDYN is not installed)."""
    if not exudyn_available():
        log("peer spatial: exudyn not installed: skipped")
        return [], "EXUDYN not installed: not run"
    import exudyn as exu

    from ..casefile import load_case
    from ..linear import linearize
    from ..modal import modes
    from ..statics import equilibrium

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for key in models:
            label, p, case, exact = SPATIAL_MODELS[key]
            path = Path(tmp) / f"{key}.toml"
            path.write_text(case(p))
            model = load_case(path)
            eq = equilibrium(model)
            SC, mbs = _exudyn_spatial(key, p)
            s_stock = _exudyn_stock(mbs)
            t_m, t_e, (lin, md), s_e = interleaved(
                repeats, lambda model=model, eq=eq: linearized_modes(model, eq, linearize, modes),
                lambda m=mbs: _exudyn_eigenvalues(m))
            s_m = np.asarray(md.eigenvalues)
            s_m = np.concatenate([s_m, np.conj(s_m[np.abs(s_m.imag) > 0])])  # listed once per pair
            ref = exact(p)
            scale = float(np.min(np.abs(ref[np.abs(ref) > 0])))
            M, C, K = (np.asarray(A.toarray() if hasattr(A, "toarray") else A)
                       for A in (lin.M, lin.P, lin.Q))
            tm, te = float(np.median(t_m)), float(np.median(t_e))
            row = {"section": "peer", "method": f"EXUDYN vs mbseig (spatial: {label})",
                   "model": label, "spatial": True, "n": int(lin.M.shape[0]),
                   "n_coordinates": len(lin.coordinate_names),
                   "exudyn_coordinates": int(mbs.systemData.ODE2Size()), "time": tm,
                   "mbseig_time": tm, "exudyn_time": te, "ratio": tm / te,
                   "mbseig_error": _scaled_set_distance(s_m, ref, scale),
                   "exudyn_error": _scaled_set_distance(s_e, ref, scale),
                   "exudyn_stock_error": _scaled_set_distance(s_stock, ref, scale),
                   "mbseig_error_nonzero": _nearest_relative(ref[np.abs(ref) > 0], s_m),
                   "exudyn_error_nonzero": _nearest_relative(ref[np.abs(ref) > 0], s_e),
                   "mbseig_eta": float(np.max(eigenvalue_backward_error(M, C, K, s_m))),
                   "exudyn_eta": float(np.max(eigenvalue_backward_error(M, C, K, s_e))),
                   "set_distance": _scaled_set_distance(s_m, s_e, scale),
                   "mbseig_solver": md.solver, "mbseig_count": int(s_m.size),
                   "exudyn_count": int(s_e.size), "repeats": repeats,
                   "exudyn_version": getattr(exu, "__version__", "?"),
                   **{k: [[float(z.real), float(z.imag)] for z in np.sort_complex(v)] for k, v in
                      (("mbseig_eigenvalues", s_m), ("exudyn_eigenvalues", s_e),
                       ("reference", ref))}}
            rows.append(row)
            log(f"peer spatial {label}: mbseig {tm * 1e3:.2f} ms ({md.solver}) "
                f"err {row['mbseig_error']:.1e} | "
                f"EXUDYN {te * 1e3:.2f} ms err {row['exudyn_error']:.1e} (stock call "
                f"{row['exudyn_stock_error']:.1e}) | ratio {row['ratio']:.2f} | sets differ by "
                f"{row['set_distance']:.1e}")
            del SC, mbs
    return rows, ""


def peer_lines(rows, note):
    chain = [r for r in rows if not r.get("spatial")]
    spatial = [r for r in rows if r.get("spatial")]
    L = ["", "## Peer: EXUDYN on a chain with non-proportional damping (same run)", ""]
    if not rows:
        return L + [note or "not run"]
    L += [("Each side from its own model of the same chain (n unit masses, k = 1000, c = 0.5 per "
          "spring, one extra dashpot c₀ = 2 to the wall), general path on both sides: mbseig "
          "`linearize` + `modes` (its dense general path), EXUDYN `ComputeODE2Eigenvalues(... "
          "computeComplexEigenvalues=True)` (matrices from its model, then the first-order "
          "system). η(s): backward error of each eigenvalue alone, σ_min(T(s)) / (|s|²‖M‖ + "
          "|s|‖C‖ + ‖K‖) by SVD, worst of the 20 smallest |s| — a reference independent of both "
          "solvers. Times: medians of interleaved runs."), ""]
    if chain:
        L += ["| n | mbseig | EXUDYN | mbseig / EXUDYN | mbseig η(s) | EXUDYN η(s) "
              "| sets differ by | runs |",
              "|---|---|---|---|---|---|---|---|"]
        for r in chain:
            L.append(f"| {r['n']} | {r['mbseig_time']:.3f} s ({r['mbseig_solver']}) | "
                     f"{r['exudyn_time']:.3f} s | "
                     f"{r['ratio']:.2f} | {r['mbseig_eta']:.0e} | {r['exudyn_eta']:.0e} | "
                     f"{r['set_distance']:.0e} | {r['repeats']} |")
    else:
        L.append("Chain rows not run.")
    L += ["", f"EXUDYN {rows[0]['exudyn_version']}."]
    L += ["", "### Peer: EXUDYN on spatial constrained models (same run)", ""]
    if not spatial:
        return L + ["Spatial models were not compared in this run."]
    L += [("Rigid bodies on spherical joints under gravity, hanging at rest in the reference "
          "configuration (EXUDYN linearizes about its initial state, mbseig about its "
          "equilibrium: the same point). EXUDYN: `CreateRigidBody` (Euler parameters), "
          "`CreateSphericalJoint`, pivot dashpots as `CreateRigidBodySpringDamper`; its "
          "`ComputeODE2Eigenvalues(computeComplexEigenvalues=True)` projects M, K, D on an SVD "
          "null space of all its constraint Jacobians (joints, Euler-parameter norms) and "
          "solves the first-order system, but its K has no load Jacobian (gravity on an offset "
          "centre of mass adds no stiffness: 'stock call' column) and no constraint-force "
          "stiffness Σλ∇²Φ. The timed EXUDYN column runs the same EXUDYN calls with the load "
          "Jacobian switched on (`computeLoadsJacobian=1`); it is exact where the joints are "
          "linear in its node coordinates (the single pendulum) and still misses Σλ∇²Φ where "
          "they are not (the joint between the two links). mbseig: a 3-D case of the same "
          "bodies, `linearize` + `modes`. Error: largest distance from the closed-form "
          "eigenvalues (pendulum: (J + m l²)s² + c s + m g l = 0 per swing axis, J_z s² + c_z s "
          "= 0; double pendulum: cases/spatial_double_pendulum.toml's source), relative to "
          "max(|s|, smallest nonzero |s|), and in parentheses over the nonzero ones only, relative "
          "to |s| (the free spins, s = 0, are double roots: a correct solver places them to "
          "about √ε of the swing frequencies); η(s) on mbseig's linearization, as for the chain. "
          "Times: model to eigenvalues (mbseig linearize + modes; EXUDYN matrices, projection, "
          "eig), medians of interleaved runs."), "",
          ("| model | coordinates (mbseig / EXUDYN) | dof | mbseig | EXUDYN | mbseig / EXUDYN | "
           "mbseig error (s ≠ 0) | EXUDYN error (s ≠ 0) | EXUDYN stock call error | mbseig η(s) | "
           "EXUDYN η(s) | sets differ by | runs |"),
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in spatial:
        L.append(f"| {r['model']} | {r['n_coordinates']} / {r['exudyn_coordinates']} | {r['n']} | "
                 f"{r['mbseig_time'] * 1e3:.2f} ms ({r['mbseig_solver']}) | "
                 f"{r['exudyn_time'] * 1e3:.2f} ms | {r['ratio']:.2f} | {r['mbseig_error']:.0e} "
                 f"({r['mbseig_error_nonzero']:.0e}) | {r['exudyn_error']:.0e} "
                 f"({r['exudyn_error_nonzero']:.0e}) | {r['exudyn_stock_error']:.0e} | "
                 f"{r['mbseig_eta']:.0e} | {r['exudyn_eta']:.0e} | {r['set_distance']:.0e} | "
                 f"{r['repeats']} |")
    return L
