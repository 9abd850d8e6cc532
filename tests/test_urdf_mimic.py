"""The mimic constraint (URDF ``<mimic>``, mbseig.model.mimic): exact derivatives against central
differences, the coordinates it couples in closed form, and the reader entry's errors."""

from __future__ import annotations

import numpy as np
import pytest
from test_urdf import joint, link, tables, write

import mbseig
from mbseig.errors import CaseError
from mbseig.model.mimic import MimicConstraint


def build_model(case):
    """The model of a 3-D case dict through mbseig's reader."""
    return mbseig.read_case(case).build()


def robot_case(tmp_path, follower_kind="prismatic", leader_kind="revolute"):
    ax = '<axis xyz="0 0.6 0.8"/>'
    path = write(tmp_path, link("base"), link("a"), link("b"),
                 joint("j1", "base", "a", leader_kind, ax, xyz="0.1 0 0.2"),
                 joint("s", "a", "b", follower_kind,
                       '<axis xyz="1 0 0"/><mimic joint="j1" multiplier="0.3" offset="0.05"/>',
                       xyz="0.3 0.1 0"))
    t = tables(path, positions={"j1": 0.4})
    return {"schema_version": 1, "dimension": 3, "gravity": [0.0, 0.0, -9.81], **t}


def mimic_of(model):
    return next(c for c in model.constraints if isinstance(c, MimicConstraint))


@pytest.mark.parametrize("kinds", [("prismatic", "revolute"), ("revolute", "revolute"),
                                   ("revolute", "prismatic"), ("prismatic", "prismatic")])
def test_derivatives_central_differences(kinds, tmp_path):
    """Φ_q, Σλ∇²Φ and γ = −q̇ᵀ∇²Φ q̇ against central differences (h = 1e-6, error O(h²)):
    tolerance 1e-7 relative to the largest entry."""
    model = build_model(robot_case(tmp_path, *kinds))
    c = mimic_of(model)
    rng = np.random.default_rng(3)
    q = model.q_init + 1e-2 * rng.standard_normal(model.q_init.size)
    qd = rng.standard_normal(q.size)
    assert abs(c.phi(model.q_init)[0]) < 1e-14  # the reference satisfies the coupling
    h, idx = 1e-6, c.idx
    J = c.jac(q)
    Jfd = np.zeros_like(J)
    H = c.hess(q, np.array([0.7]))
    Hfd = np.zeros_like(H)
    for k, i in enumerate(idx):
        e = np.zeros(q.size)
        e[i] = h
        Jfd[:, k] = (c.phi(q + e) - c.phi(q - e)) / (2 * h)
        Hfd[:, k] = 0.7 * (c.jac(q + e)[0] - c.jac(q - e)[0]) / (2 * h)
    assert np.max(np.abs(J - Jfd)) < 1e-7 * np.max(np.abs(J))
    assert np.max(np.abs(H - Hfd)) < 1e-7 * max(np.max(np.abs(H)), 1.0)
    Hq = c.hess(q, np.ones(1))
    assert np.isclose(c.gamma(q, qd)[0], -(qd[idx] @ Hq @ qd[idx]), rtol=1e-12, atol=1e-14)


def test_slide_and_angle_values(tmp_path):
    """Translating the follower body by δ along the prismatic axis gives c_F = δ; the leader's
    angle is that of a rotation of body a about the leader's axis through its joint point
    (Rodrigues), so Φ = δ − 0.3 θ."""
    case = robot_case(tmp_path)
    model = build_model(case)
    c = mimic_of(model)
    names = list(model.coordinate_names)
    joints = {j["name"]: j for j in case["joints"]}
    a_s = np.array(joints["s"]["axis"])
    q = model.q_init.copy()
    delta = 0.01
    for k, x in enumerate("xyz"):
        q[names.index(f"b.{x}")] += delta * a_s[k]
    assert np.isclose(c.phi(q)[0], delta, rtol=1e-12)
    # rotate body a (and its frame) about j1's axis through j1's point by θ
    theta, a1, p1 = 0.02, np.array(joints["j1"]["axis"]), np.array(joints["j1"]["at"])
    K = np.array([[0, -a1[2], a1[1]], [a1[2], 0, -a1[0]], [-a1[1], a1[0], 0]])
    R = np.eye(3) + np.sin(theta) * K + (1 - np.cos(theta)) * K @ K
    q2 = model.q_init.copy()
    r0 = np.array([q2[names.index(f"a.{x}")] for x in "xyz"])
    for k, x in enumerate("xyz"):
        q2[names.index(f"a.{x}")] = (p1 + R @ (r0 - p1))[k]
    for v in "uvw":
        e = np.array([q2[names.index(f"a.{v}.{x}")] for x in "xyz"])
        for k, x in enumerate("xyz"):
            q2[names.index(f"a.{v}.{x}")] = (R @ e)[k]
    # b did not move: its slide relative to a changes too; take it from the same map
    slide = c.follower.evaluate(c.follower.rows.aff(q2))[0]
    assert np.isclose(c.phi(q2)[0], slide - 0.3 * theta, rtol=0, atol=1e-13)
    assert np.isclose(c.leader.evaluate(c.leader.rows.aff(q2))[0], theta, rtol=1e-12)


def test_reader_errors(tmp_path):
    case = robot_case(tmp_path)
    bad = dict(case, joints=[*case["joints"][:3],
                             {"type": "mimic", "name": "x", "joint": "s", "leader": "nope"}])
    with pytest.raises(CaseError, match="leader 'nope' is not a revolute, cylindrical or "
                                        "prismatic joint declared before"):
        build_model(bad)
    bad = dict(case, joints=[*case["joints"][:3],
                             {"type": "mimic", "name": "x", "joint": "s", "leader": "s"}])
    with pytest.raises(CaseError, match="cannot follow itself"):
        build_model(bad)
