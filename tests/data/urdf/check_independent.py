#!/usr/bin/env python3
"""Independent check of the Pinocchio numbers: a plain-numpy URDF reader (no Pinocchio).

For every model in reference/*.json it recomputes, from the URDF text alone,
  M(q) = sum_b m_b Jv_b^T Jv_b + Jw_b^T R_b I_b R_b^T Jw_b   (Jacobians of the COM / body rotation)
  g(q) = -sum_b m_b Jv_b^T g_vec                              (torque that holds the robot)
at q0 and q*, with fixed joints as rigid attachments and <mimic> joints by q_full = G q + b,
and compares with the M stored in the JSON and with the equilibrium condition
K (q* - q0) + g(q*) = 0.  The K_total of the gravity cases is compared with K + d g/dq
by central differences of this g.

URDF conventions used: <origin rpy> is R = Rz(yaw) Ry(pitch) Rx(roll); <inertia> entries are
the tensor entries (ixy = I_xy of the matrix, not its negative) about the COM in the
<inertial><origin> frame; joint axis given in the joint frame (normalised here).
"""
import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent
GRAVITY = np.array([0, 0, -9.81])   # the gravity vector of the URDF world frame (m/s^2)


def rpy(r, p, y):
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def axis_rot(a, t):
    a = a / np.linalg.norm(a)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(t) * K + (1 - np.cos(t)) * K @ K


def origin(el):
    o = el.find("origin") if el is not None else None
    if o is None:
        return np.zeros(3), np.eye(3)
    xyz = np.array([float(v) for v in o.get("xyz", "0 0 0").split()])
    r = [float(v) for v in o.get("rpy", "0 0 0").split()]
    return xyz, rpy(*r)


class Robot:
    def __init__(self, path):
        root = ET.parse(path).getroot()
        self.links = {link.get("name"): link for link in root.findall("link")}
        self.joints = root.findall("joint")
        self.child_joint = {j.find("child").get("link"): j for j in self.joints}
        roots = [name for name in self.links if name not in self.child_joint]
        assert len(roots) == 1
        self.root = roots[0]
        self.mimic = {}
        for j in self.joints:
            m = j.find("mimic")
            if m is not None:
                self.mimic[j.get("name")] = (m.get("joint"), float(m.get("multiplier", 1)),
                                             float(m.get("offset", 0)))

    def full_q(self, names, q):
        qf = dict(zip(names, q, strict=True))
        for n, (src, a, off) in self.mimic.items():
            if n not in qf:
                qf[n] = a * qf[src] + off
        return qf

    def kinematics(self, qf):
        """World pose of every link frame and, per moving joint, its world axis and origin."""
        pose = {self.root: (np.zeros(3), np.eye(3))}
        jinfo = {}
        ancestors = {self.root: []}
        order = [self.root]
        i = 0
        while i < len(order):
            parent = order[i]
            i += 1
            for j in self.joints:
                if j.find("parent").get("link") != parent:
                    continue
                c = j.find("child").get("link")
                p, R = pose[parent]
                xyz, Ro = origin(j)
                pj, Rj = p + R @ xyz, R @ Ro
                t = j.get("type")
                anc = list(ancestors[parent])
                if t in ("revolute", "continuous", "prismatic"):
                    ax = j.find("axis")
                    xyz_axis = ax.get("xyz") if ax is not None else "1 0 0"
                    a = np.array([float(v) for v in xyz_axis.split()])
                    a = a / np.linalg.norm(a)
                    aw = Rj @ a
                    jinfo[j.get("name")] = (t, aw, pj)
                    anc.append(j.get("name"))
                    if t == "prismatic":
                        pj = pj + aw * qf[j.get("name")]
                    else:
                        Rj = Rj @ axis_rot(a, qf[j.get("name")])
                elif t != "fixed":
                    raise ValueError(t)
                pose[c] = (pj, Rj)
                ancestors[c] = anc
                order.append(c)
        return pose, jinfo, ancestors

    def M_g(self, names, q, G, gvec=GRAVITY):
        qf = self.full_q(names, q)
        full = list(G.keys())
        pose, jinfo, anc = self.kinematics(qf)
        nf = len(full)
        M = np.zeros((nf, nf))
        g = np.zeros(nf)
        for ln, el in self.links.items():
            ine = el.find("inertial")
            if ine is None:
                continue
            m = float(ine.find("mass").get("value"))
            if m == 0 or ln == self.root:
                continue
            a = {k: float(v) for k, v in ine.find("inertia").attrib.items()}
            Ic = np.array([[a["ixx"], a["ixy"], a["ixz"]], [a["ixy"], a["iyy"], a["iyz"]],
                           [a["ixz"], a["iyz"], a["izz"]]])
            p, R = pose[ln]
            xyz, Ri = origin(ine)
            c = p + R @ xyz
            Iw = (R @ Ri) @ Ic @ (R @ Ri).T
            Jv = np.zeros((3, nf))
            Jw = np.zeros((3, nf))
            for jn in anc[ln]:
                t, aw, pj = jinfo[jn]
                k = full.index(jn)
                if t == "prismatic":
                    Jv[:, k] = aw
                else:
                    Jv[:, k] = np.cross(aw, c - pj)
                    Jw[:, k] = aw
            M += m * Jv.T @ Jv + Jw.T @ Iw @ Jw
            g += -m * Jv.T @ gvec
        Gm = np.array([G[n] for n in full])
        return Gm.T @ M @ Gm, Gm.T @ g


def main():
    worst = 0.0
    for f in sorted((ROOT / "reference").glob("*.json")):
        r = json.loads(f.read_text())
        rob = Robot(ROOT / r["urdf"].removeprefix("data/"))
        names = [c["name"] for c in r["coordinates"]]
        # G rows per full joint (v order of the URDF moving joints)
        moving = [j.get("name") for j in rob.joints
                  if j.get("type") in ("revolute", "continuous", "prismatic")]
        G = {}
        for n in moving:
            row = np.zeros(len(names))
            if n in names:
                row[names.index(n)] = 1.0
            else:
                src, a, off = rob.mimic[n]
                row[names.index(src)] = a
            G[n] = row
        if not r["mimic_as_constraint"]:
            rob.mimic = {}
        q0 = np.array(r["q0"])
        qs = np.array(r["equilibrium"]["q_star"])
        K = np.diag(r["k"])
        out = {}
        M0, _ = rob.M_g(names, q0, G)
        out["M(q0)"] = (np.max(np.abs(M0 - np.array(r["cases"]["no_gravity_d_uniform"]["M"])))
                        / np.max(np.abs(M0)))
        Ms, gs = rob.M_g(names, qs, G)
        out["M(q*)"] = (np.max(np.abs(Ms - np.array(r["cases"]["gravity_d_uniform"]["M"])))
                        / np.max(np.abs(Ms)))
        out["K(q*-q0)+g(q*)"] = np.max(np.abs(K @ (qs - q0) + gs))
        h = 1e-6
        dg = np.array([(rob.M_g(names, qs + h * e, G)[1] - rob.M_g(names, qs - h * e, G)[1])
                       / (2 * h) for e in np.eye(len(names))]).T
        Kt = np.array(r["cases"]["gravity_d_uniform"]["K_total"])
        out["K_total vs K+dg_fd"] = np.max(np.abs(Kt - K - 0.5 * (dg + dg.T))) / np.max(np.abs(Kt))
        print(f"{r['model']:14s} " + "  ".join(f"{k}: {v:.1e}" for k, v in out.items()))
        worst = max(worst, out["M(q0)"], out["M(q*)"])
    print("worst relative M deviation", f"{worst:.1e}")
    return 0 if worst < 1e-12 else 1


if __name__ == "__main__":
    sys.exit(main())
