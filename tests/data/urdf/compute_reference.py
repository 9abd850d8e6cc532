#!/usr/bin/env python3
"""Reference eigenvalues of URDF robots with joint springs, computed with Pinocchio.

Needs Pinocchio, which the test suite does not: ``pip install pin mpmath scipy numpy`` (the
versions used are in requirements.txt: pin 4.1.0), then ``python compute_reference.py``.
Writes reference/<model>.json and reference/TABLES.md.  The "urdf" field of the JSON keeps the
layout where the references were made (data/<robot>/...); the robots are in <robot>/ here.

Model (fixed base, joint coordinates q of the Pinocchio model, i.e. the independent
coordinates; a <mimic> joint is not a coordinate when the model is built with mimic=True):

    M(q) q'' + C(q, q') q' + g(q) = tau                      (Pinocchio's convention)
    tau = -K (q - q0) - D q'                                 (joint springs and dampers)

g(q) = computeGeneralizedGravity = rnea(q, 0, 0) = +dV/dq (V: potential energy) is the
torque needed to HOLD the robot; the gravity load on the right-hand side is -g.

    equilibrium q*:   K (q* - q0) + g(q*) = 0                (Newton, Jacobian K + dg/dq)
    linearization :   M(q*) s^2 + D s + (K + dg/dq(q*)) = 0

Without gravity q* = q0.  Eigenvalues: mpmath (50 digits) on the companion matrix built
from the double-precision M, D, K_total that are also stored in the JSON, cross-checked
against scipy.
"""
from __future__ import annotations

import hashlib
import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import mpmath as mp
import numpy as np
import pinocchio as pin
import scipy
import scipy.linalg as sla

ROOT = Path(__file__).resolve().parent
OUT = ROOT / "reference"
G0 = 9.81
MP_DPS = 50

# --------------------------------------------------------------------------- models
MODELS = {
    "ur5": dict(
        urdf="data/ur5/ur5_robot.urdf", mimic=False,
        q0=[0.3, -1.1, 1.4, -0.9, 1.2, 0.5],
        k=500.0, d=2.0,
    ),
    "panda": dict(
        urdf="data/panda/panda.urdf", mimic=True,
        # 7 arm joints [rad] + panda_finger_joint1 [m]; panda_finger_joint2 = finger_joint1 (mimic)
        q0=[0.2, -0.6, 0.3, -2.0, 0.4, 1.7, 0.6, 0.02],
        k=500.0, d=2.0,
    ),
    "panda_nomimic": dict(
        urdf="data/panda/panda.urdf", mimic=False,
        q0=[0.2, -0.6, 0.3, -2.0, 0.4, 1.7, 0.6, 0.02, 0.02],
        k=500.0, d=2.0,
    ),
    "toy": dict(
        urdf="data/toy/toy_rpm.urdf", mimic=True,
        q0=[0.4, 0.15],            # j1 [rad], j2 [m]; j3 = -0.5*j1 + 0.1 (mimic)
        k=[60.0, 400.0], d=2.0,
    ),
    "toy_nomimic": dict(
        urdf="data/toy/toy_rpm.urdf", mimic=False,
        q0=[0.4, 0.15, -0.1],      # j3 at its mimic value, but free
        k=[60.0, 400.0, 60.0], d=2.0,
    ),
    # fixed-joint point masses (zero inertia) merged into their parent (issue 39)
    "talos_left_arm": dict(
        urdf="data/talos/talos_left_arm.urdf", mimic=False,
        # arm_left_2..7 + gripper_left_joint (arm_left_1_link is the root), within the limits
        q0=[0.4, 0.3, -1.2, 0.5, 0.3, 0.2, -0.5],
        k=300.0, d=2.0,
    ),
    "so101": dict(
        urdf="data/so101/so101.urdf", mimic=False,
        q0=[0.3, -0.5, 0.8, 0.4, 0.2, 0.3],
        k=20.0, d=0.05,
    ),
}


# --------------------------------------------------------------------------- helpers
def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def build(urdf: Path, mimic: bool, gravity: bool):
    model = pin.buildModelFromUrdf(str(urdf), mimic)
    model.gravity.linear = np.array([0.0, 0.0, -G0 if gravity else 0.0])
    return model, model.createData()


def coord_joints(model):
    """(name, shortname) of the joints that own a velocity coordinate, in v order."""
    out = []
    for jid in range(1, model.njoints):
        j = model.joints[jid]
        if j.nv == 1:
            out.append((model.names[jid], j.shortname(), j.idx_v))
        elif j.nv != 0:
            raise ValueError("only 1-dof joints expected")
    out.sort(key=lambda t: t[2])
    return [(n, s) for n, s, _ in out]


def mass_matrix(model, data, q):
    M = np.array(pin.crba(model, data, q))
    M = np.triu(M) + np.triu(M, 1).T          # crba guarantees only the upper triangle
    return M


def gravity(model, data, q):
    return np.array(pin.computeGeneralizedGravity(model, data, q)).copy()


# For models built with mimic=True, Pinocchio 4.1 refuses computeGeneralizedGravityDerivatives
# and computePotentialEnergy ("does not support Joint Mimic type").  For those models the
# derivative is taken from the model built with mimic=False (mimic joints as free joints) by
# the chain rule: q_full = G q + b (constant G, b)  =>  dg/dq = G^T (dg_full/dq_full) G.
# It is checked against central differences of the mimic model's own computeGeneralizedGravity.
_FULL = {}   # id(reduced model) -> (full model, full data, G, b)


def gravity_jac(model, data, q):
    if id(model) in _FULL:
        mf, df, G, b = _FULL[id(model)]
        return G.T @ np.array(pin.computeGeneralizedGravityDerivatives(mf, df, G @ q + b)) @ G
    return np.array(pin.computeGeneralizedGravityDerivatives(model, data, q)).copy()


def fd_jac(f, q, h=1e-6):
    n = len(q)
    cols = []
    for i in range(n):
        e = np.zeros(n)
        e[i] = h
        cols.append((f(q + e) - f(q - e)) / (2 * h))
    return np.array(cols).T


def equilibrium(model, data, q0, K, tol=1e-15, maxit=50):
    q = q0.copy()
    hist = []
    for it in range(1, maxit + 1):
        r = K @ (q - q0) + gravity(model, data, q)
        J = K + gravity_jac(model, data, q)
        dq = np.linalg.solve(J, -r)
        q = q + dq
        hist.append(float(np.max(np.abs(dq))))
        if hist[-1] <= tol * max(1.0, np.max(np.abs(q))) and it >= 3:
            break
    r = K @ (q - q0) + gravity(model, data, q)
    return q, it, float(np.max(np.abs(r))), hist


def companion_mp(M, D, K):
    n = M.shape[0]
    Mm, Dm, Km = (mp.matrix(X.tolist()) for X in (M, D, K))
    Mi = mp.inverse(Mm)
    A = mp.zeros(2 * n, 2 * n)
    MiK, MiD = Mi * Km, Mi * Dm
    for i in range(n):
        A[i, n + i] = 1
        for j in range(n):
            A[n + i, j] = -MiK[i, j]
            A[n + i, n + j] = -MiD[i, j]
    return A


def sort_eigs(s):
    s = np.asarray(s, dtype=complex)
    # primary key: imaginary part, then real part (values rounded to 12 significant
    # digits for the key only, so that conjugate partners and clusters order stably)
    scale = max(1.0, float(np.max(np.abs(s))))
    key = [(round(z.imag / scale, 12), round(z.real / scale, 12)) for z in s]
    order = sorted(range(len(s)), key=lambda i: key[i])
    return s[order]


def eigenvalues(M, D, K):
    """Return (sorted mpmath eigenvalues as complex, info dict)."""
    n = M.shape[0]
    mp.mp.dps = MP_DPS
    A = companion_mp(M, D, K)
    ev = mp.eig(A, left=False, right=False)
    # values below 1e-30 relative are round-off of the 50-digit arithmetic: set them to 0
    # (exactly imaginary pairs when D = 0 and K_total is symmetric, exactly real overdamped roots)
    s_mp = []
    for z in ev:
        r = abs(z)
        re = mp.mpf(0) if abs(z.real) < mp.mpf(10) ** -30 * r else z.real
        im = mp.mpf(0) if abs(z.imag) < mp.mpf(10) ** -30 * r else z.imag
        s_mp.append(complex(float(re), float(im)))
    s_mp = np.array(s_mp)
    # make conjugate pairs exactly conjugate (the pencil is real)
    s_mp = sort_eigs(s_mp)
    # cross-check: scipy on the generalized pencil
    Z, eye = np.zeros((n, n)), np.eye(n)
    Aa = np.block([[Z, eye], [-K, -D]])
    Bb = np.block([[eye, Z], [Z, M]])
    s_sp = sort_eigs(sla.eig(Aa, Bb, right=False))
    # match scipy to mpmath greedily
    used, dev = set(), 0.0
    for z in s_mp:
        j = min((j for j in range(len(s_sp)) if j not in used), key=lambda j: abs(s_sp[j] - z))
        used.add(j)
        dev = max(dev, abs(s_sp[j] - z) / max(abs(z), 1e-300))
    # backward error of each mp eigenvalue for the double pencil (smallest singular value)
    nM, nD, nK = (np.linalg.norm(X, 2) for X in (M, D, K))
    eta = 0.0
    for z in s_mp:
        P = M * z * z + D * z + K
        smin = np.linalg.svd(P, compute_uv=False)[-1]
        eta = max(eta, smin / (nM * abs(z) ** 2 + nD * abs(z) + nK))
    return s_mp, dict(max_rel_dev_scipy_vs_mpmath=dev, max_backward_error=eta)


def mimic_map(urdf: Path, full, red):
    """G, b with q_full = G q_red + b (v order), from the <mimic> tags of the URDF."""
    root = ET.parse(urdf).getroot()
    mim = {}
    for j in root.findall("joint"):
        m = j.find("mimic")
        if m is not None:
            mim[j.get("name")] = (m.get("joint"), float(m.get("multiplier", 1.0)),
                                  float(m.get("offset", 0.0)))
    fn = [n for n, _ in coord_joints(full)]
    rn = [n for n, _ in coord_joints(red)]
    G = np.zeros((len(fn), len(rn)))
    b = np.zeros(len(fn))
    for i, n in enumerate(fn):
        if n in mim:
            src, a, off = mim[n]
            G[i, rn.index(src)] = a
            b[i] = off
        else:
            G[i, rn.index(n)] = 1.0
    return G, b, mim


def inertia_checks(urdf: Path):
    """Per link: mass, eigenvalues of the URDF inertia tensor, triangle inequality."""
    root = ET.parse(urdf).getroot()
    rows = []
    for ln in root.findall("link"):
        ine = ln.find("inertial")
        if ine is None:
            rows.append(dict(link=ln.get("name"), inertial=False))
            continue
        m = float(ine.find("mass").get("value"))
        a = {k: float(v) for k, v in ine.find("inertia").attrib.items()}
        inertia = np.array([[a["ixx"], a["ixy"], a["ixz"]], [a["ixy"], a["iyy"], a["iyz"]],
                            [a["ixz"], a["iyz"], a["izz"]]])
        ev = np.linalg.eigvalsh(inertia)
        tri = bool(ev[0] + ev[1] >= ev[2] - 1e-12) if m > 0 else None
        rows.append(dict(link=ln.get("name"), inertial=True, mass=m,
                         principal_moments=ev.tolist(), positive=bool(ev[0] > 0) if m > 0 else None,
                         triangle_inequality=tri))
    return rows


def urdf_features(urdf: Path):
    root = ET.parse(urdf).getroot()
    j = root.findall("joint")
    return dict(
        joints_by_type={t: [x.get("name") for x in j if x.get("type") == t]
                        for t in sorted({x.get("type") for x in j})},
        mimic=[dict(mimic_joint=x.get("name"), **x.find("mimic").attrib) for x in j
               if x.find("mimic") is not None],
        links_without_inertial=[ln.get("name") for ln in root.findall("link")
                                if ln.find("inertial") is None],
        links_with_zero_mass=[ln.get("name") for ln in root.findall("link")
                              if ln.find("inertial") is not None
                              and float(ln.find("inertial/mass").get("value")) == 0.0],
        dynamics={x.get("name"): dict(x.find("dynamics").attrib) for x in j
                  if x.find("dynamics") is not None},
    )


def merged_bodies(model, data, q):
    """Pinocchio's body of each joint (the links on fixed joints merged into it) in world axes
    at q: mass, centre of mass, inertia about it; and the joint of every link frame."""
    pin.forwardKinematics(model, data, q)
    bodies = []
    for jid in range(1, model.njoints):
        Y, oMi = model.inertias[jid], data.oMi[jid]
        R = np.array(oMi.rotation)
        bodies.append(dict(joint=model.names[jid], mass=float(Y.mass),
                           com=(np.array(oMi.translation) + R @ np.array(Y.lever)).tolist(),
                           inertia=(R @ np.array(Y.inertia) @ R.T).tolist()))
    links = {f.name: model.names[f.parentJoint] for f in model.frames
             if f.type == pin.FrameType.BODY}
    return bodies, links


def condition_numbers(M, D, K, s):
    """Normwise relative condition number of each eigenvalue of M s^2 + D s + K (Tisseur,
    Linear Algebra Appl. 309 (2000), Thm 5): (|s|^2 |M| + |s| |D| + |K|) |x| |y| /
    (|s| |y^H (2 s M + D) x|), x, y right and left null vectors (smallest singular vectors)."""
    nM, nD, nK = (np.linalg.norm(X, 2) for X in (M, D, K))
    out = []
    for z in s:
        U, _, Vh = np.linalg.svd(M * z * z + D * z + K)
        x, y = Vh[-1].conj(), U[:, -1]
        out.append(float((abs(z) ** 2 * nM + abs(z) * nD + nK)
                         / (abs(z) * abs(y.conj() @ (2 * z * M + D) @ x))))
    return out


def cplx_list(s):
    return [[float(z.real), float(z.imag)] for z in s]


def cplx_str(s):
    return [f"{z.real:+.16e} {z.imag:+.16e}j" for z in s]


# --------------------------------------------------------------------------- main work
def run_model(name, spec):
    urdf = ROOT / spec["urdf"].removeprefix("data/")
    mimic = spec["mimic"]
    mg, dg_ = build(urdf, mimic, True)
    m0, d0 = build(urdf, mimic, False)
    if mimic:
        for red in (mg, m0):
            full = build(urdf, False, red is mg)
            G_, b_, _ = mimic_map(urdf, full[0], red)
            _FULL[id(red)] = (full[0], full[1], G_, b_)
    joints = coord_joints(mg)
    n = mg.nv
    assert mg.nq == n, "joint spaces with nq != nv are not expected here"
    q0 = np.array(spec["q0"], float)
    k = np.broadcast_to(np.array(spec["k"], float), (n,)).copy()
    d = np.broadcast_to(np.array(spec["d"], float), (n,)).copy()
    K, D_uni, D_urdf = np.diag(k), np.diag(d), np.diag(np.array(mg.damping))

    checks = {}
    # --- sign convention: g == rnea(q,0,0) == +dV/dq; dg/dq == FD of g
    g0 = gravity(mg, dg_, q0)
    checks["g_minus_rnea_q_0_0"] = float(np.max(np.abs(
        g0 - pin.rnea(mg, dg_, q0, np.zeros(n), np.zeros(n)))))
    # computePotentialEnergy refuses mimic models: use the full model at q_full = G q + b
    if mimic:
        mf_, df_ = build(urdf, False, True)
        Gm, bm, _ = mimic_map(urdf, mf_, mg)

        def V(q):
            return np.array([pin.computePotentialEnergy(mf_, df_, Gm @ q + bm)])
    else:
        def V(q):
            return np.array([pin.computePotentialEnergy(mg, dg_, q)])
    dVdq = fd_jac(V, q0)[0]
    checks["g_minus_dV_dq_fd"] = float(np.max(np.abs(g0 - dVdq)))
    checks["g_plus_dV_dq_fd"] = float(np.max(np.abs(g0 + dVdq)))
    # crba against columns of rnea(q, 0, e_i) - rnea(q, 0, 0) (model without mimic joints only)
    if not mimic:
        Mq = mass_matrix(mg, dg_, q0)
        Mr = np.array([pin.rnea(mg, dg_, q0, np.zeros(n), e) - g0 for e in np.eye(n)]).T
        checks["crba_minus_rnea_columns"] = float(np.max(np.abs(Mq - Mr)))
    Jg = gravity_jac(mg, dg_, q0)
    checks["dgdq_minus_fd"] = float(np.max(np.abs(Jg - fd_jac(lambda q: gravity(mg, dg_, q), q0))))
    checks["dgdq_asymmetry"] = float(np.max(np.abs(Jg - Jg.T)))

    # --- mimic: compare with the full model reduced by q_full = G q + b
    if mimic:
        mf, df = build(urdf, False, True)
        G, b, mim = mimic_map(urdf, mf, mg)
        qf = G @ q0 + b
        checks["mimic_M_minus_GtMG"] = float(np.max(np.abs(
            mass_matrix(mg, dg_, q0) - G.T @ mass_matrix(mf, df, qf) @ G)))
        checks["mimic_g_minus_Gtg"] = float(np.max(np.abs(g0 - G.T @ gravity(mf, df, qf))))
        mimic_info = dict(G=G.tolist(), b=b.tolist(),
                          full_joint_names=[x for x, _ in coord_joints(mf)], urdf_mimic=mim)
    else:
        mimic_info = None

    # --- equilibrium with gravity
    qs, iters, res, hist = equilibrium(mg, dg_, q0, K)
    eq = dict(q_star=qs.tolist(), newton_iterations=iters, residual_inf=res,
              newton_step_history=hist, gravity_torque_at_q0=g0.tolist(),
              gravity_torque_at_q_star=gravity(mg, dg_, qs).tolist())

    cases = {}

    def add(case, model, data, q, D, Kt, note):
        # K + dg/dq is symmetric in exact arithmetic (dg/dq is the Hessian of V); the stored
        # and used matrix is its symmetric part (the asymmetry removed is listed in checks)
        Kt = 0.5 * (Kt + Kt.T)
        M = mass_matrix(model, data, q)
        s, info = eigenvalues(M, D, Kt)
        w = np.linalg.eigvalsh(0.5 * (Kt + Kt.T))
        cases[case] = dict(note=note, q=q.tolist(), M=M.tolist(), D=D.tolist(), K_total=Kt.tolist(),
                           K_total_min_eig=float(w[0]), eigenvalues=cplx_list(s),
                           eigenvalues_str=cplx_str(s), **info)
        if name in MERGED:
            cases[case]["condition"] = condition_numbers(M, D, Kt, s)

    add("no_gravity_d_uniform", m0, d0, q0, D_uni, K, "M(q0) s^2 + d I s + K")
    add("gravity_d_uniform", mg, dg_, qs, D_uni, K + gravity_jac(mg, dg_, qs),
        "M(q*) s^2 + d I s + (K + dg/dq(q*))")
    add("no_gravity_d_urdf", m0, d0, q0, D_urdf, K, "M(q0) s^2 + D_urdf s + K")
    add("gravity_d_urdf", mg, dg_, qs, D_urdf, K + gravity_jac(mg, dg_, qs),
        "M(q*) s^2 + D_urdf s + (K + dg/dq(q*))")

    alt = None
    if mimic:
        # variant: a spring k and damper d on EVERY URDF joint, mimic joints included,
        # reduced to the independent coordinates: K_r = G^T K_full G, D_r = G^T D_full G,
        # spring rest positions q_full0 = G q0 + b (so no torque at q0).
        mf, df = build(urdf, False, True)
        nf = mf.nv
        kf = np.array([k[[x for x, _ in joints].index(nm)] if nm in [x for x, _ in joints]
                       else k[[x for x, _ in joints].index(mimic_info["urdf_mimic"][nm][0])]
                       for nm in mimic_info["full_joint_names"]])
        G = np.array(mimic_info["G"])
        Kr = G.T @ np.diag(kf) @ G
        Dr = G.T @ (d[0] * np.eye(nf)) @ G
        qs2, it2, res2, _ = equilibrium(mg, dg_, q0, Kr)
        alt = dict(k_full=kf.tolist(), K_reduced=Kr.tolist(), D_reduced=Dr.tolist(),
                   q_star=qs2.tolist(), newton_iterations=it2, residual_inf=res2)
        add("allsprings_no_gravity_d_uniform", m0, d0, q0, Dr, Kr,
            "springs/dampers also on mimic joints: M(q0) s^2 + G^T d G s + G^T K G")
        add("allsprings_gravity_d_uniform", mg, dg_, qs2, Dr, Kr + gravity_jac(mg, dg_, qs2),
            "springs/dampers also on mimic joints, with gravity at its own q*")

    extra = {}
    if name in MERGED:
        bodies, frames = merged_bodies(mg, dg_, q0)
        extra = dict(merged_bodies_at_q0=bodies, frame_joint=frames)
    return dict(
        **extra,
        model=name, urdf=spec["urdf"], urdf_sha256=sha256(urdf), mimic_as_constraint=mimic,
        versions=dict(pinocchio=pin.__version__, numpy=np.__version__, scipy=scipy.__version__,
                      mpmath=mp.__version__, python=sys.version.split()[0]),
        convention=("M(q) q'' + C q' + g(q) = tau, "
                    "g = computeGeneralizedGravity = rnea(q,0,0) = +dV/dq; "
                    "tau = -K (q - q0) - D q'; equilibrium K (q*-q0) + g(q*) = 0; "
                    "eigenproblem det(M(q*) s^2 + D s + K + dg/dq(q*)) = 0; fixed base; "
                    "gravity (0,0,-9.81) in the URDF root frame; SI units (rad, m, kg)."),
        gravity=[0.0, 0.0, -G0],
        coordinates=[dict(name=a, pinocchio_type=b) for a, b in joints],
        q0=q0.tolist(), k=k.tolist(), d_uniform=d.tolist(), d_urdf=np.array(mg.damping).tolist(),
        total_mass_moving_and_base=float(sum(i.mass for i in mg.inertias)),
        equilibrium=eq, mimic=mimic_info, allsprings_variant=alt,
        checks=checks, urdf_features=urdf_features(urdf), inertia_checks=inertia_checks(urdf),
        cases=cases,
    )


def table(res):
    lines = [f"### {res['model']}  (`{res['urdf']}`, "
             f"mimic as constraint: {res['mimic_as_constraint']})", ""]
    names = [c["name"] for c in res["coordinates"]]
    lines.append("| coordinate | q0 | q* (gravity) | k | d | d_urdf |")
    lines.append("|---|---|---|---|---|---|")
    for i, nm in enumerate(names):
        lines.append(f"| {nm} | {res['q0'][i]!r} | {res['equilibrium']['q_star'][i]:.16e} | "
                     f"{res['k'][i]!r} | {res['d_uniform'][i]!r} | {res['d_urdf'][i]!r} |")
    if res["allsprings_variant"]:
        a = res["allsprings_variant"]
        lines.append("")
        lines.append("allsprings variant q* = ["
                     + ", ".join(f"{x:.16e}" for x in a["q_star"]) + "]")
    lines.append("")
    for cname, c in res["cases"].items():
        lines.append(f"**{cname}** — {c['note']}  (scipy vs mpmath max rel. dev. "
                     f"{c['max_rel_dev_scipy_vs_mpmath']:.1e}, "
                     f"backward error {c['max_backward_error']:.1e})")
        lines.append("")
        lines.append("```")
        lines.extend(c["eigenvalues_str"])
        lines.append("```")
        lines.append("")
    return "\n".join(lines)


MERGED = ("talos_left_arm", "so101")  # models whose merged bodies and condition numbers are kept


def main(names=()):
    """Every model, or only the named ones (``python compute_reference.py so101``)."""
    OUT.mkdir(exist_ok=True)
    md = ["# Reference eigenvalues (generated by compute_reference.py)", ""]
    for name, spec in MODELS.items():
        if names and name not in names:
            continue
        res = run_model(name, spec)
        (OUT / f"{name}.json").write_text(json.dumps(res, indent=1) + "\n")
        md.append(table(res))
        c = res["checks"]
        print(f"{name}: nv={len(res['q0'])} newton it={res['equilibrium']['newton_iterations']} "
              f"res={res['equilibrium']['residual_inf']:.1e} checks=" +
              ", ".join(f"{k}={v:.1e}" for k, v in c.items()))
        for cname, cc in res["cases"].items():
            print(f"   {cname}: dev={cc['max_rel_dev_scipy_vs_mpmath']:.1e} "
                  f"eta={cc['max_backward_error']:.1e} "
                  f"Kmin={cc['K_total_min_eig']:.3g}")
    if not names:
        (OUT / "TABLES.md").write_text("\n".join(md) + "\n")


if __name__ == "__main__":
    main(tuple(sys.argv[1:]))
