"""Robots from URDF (DESIGN §8): the two-link arm example against a hand-written joint-space
model, geometry in closed form, massless-link merging, every bad-URDF message (one line, exit 2
from the CLI), ``mbseig import-urdf``, and two public robots of different makers (Universal
Robots UR5, Franka Emika Panda) against Pinocchio's joint-space model.

References and tolerances:
- two-link arm: :func:`arm_joint_space`, written by hand from the URDF numbers (independent of
  mbseig), relative 1e-9 on every eigenvalue;
- robots: tests/data/urdf/reference/<model>.json, eigenvalues of M(q*) s² + D s + (K + ∂g/∂q)
  with M, g, ∂g/∂q from Pinocchio 4.1.0 (tests/data/urdf/compute_reference.py, which needs
  ``pip install pin``; Pinocchio is not needed here: the JSON is data), eigenvalues by mpmath at
  50 digits; relative 1e-9 on every eigenvalue;
- geometry: closed forms named in each test (rotation of a tensor, URDF rpy convention).
"""

from __future__ import annotations

import json
import math
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import mbseig
from mbseig.casefile.urdf import expand_urdf, read_urdf, rpy_matrix, urdf_tables
from mbseig.casefile.writer import to_toml
from mbseig.cli import main
from mbseig.errors import CaseError
from mbseig.studies import analyze

DATA = Path(__file__).resolve().parent / "data" / "urdf"
# the format example of DESIGN §8 (shared examples), or its copy under tests/data
# the format examples of DESIGN §8 (../shared/examples beside the checkout)
SHARED = Path(__file__).resolve().parents[2] / "shared" / "examples" / "two_link_arm.toml"
ARM = SHARED if SHARED.exists() else DATA / "arm" / "two_link_arm.toml"


def cli(capsys, *argv):
    """``mbseig ARGV`` in process: (exit code, stdout, stderr)."""
    capsys.readouterr()
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def sorted_upper(s):
    """Eigenvalues with Im s >= 0 (a conjugate pair once), sorted."""
    s = np.asarray(s, complex)
    return np.sort_complex(s[s.imag >= 0])


# ---------------------------------------------------------------------------------------------
# The two-link arm: the format example through `mbseig modes --json` vs a joint-space model
# ---------------------------------------------------------------------------------------------
def arm_joint_space(g=9.81):
    """Eigenvalues of the two-link arm of two_link_arm.urdf in its joint angles (q1 shoulder,
    q2 elbow, both about +y), written from the URDF numbers by hand, independent of mbseig:

    rotation about +y by φ maps (x, z) → (x cos φ + z sin φ, −x sin φ + z cos φ); link 1 turns by
    φ1 = q1 about the shoulder (0, 0, 0.1), link 2 by φ2 = q1 + q2 about the elbow, which sits
    0.4 up link 1; CoMs 0.2 up link 1 and 0.15 up link 2.  Both rotations are about y, so each
    link's rotary inertia is its Iyy (0.03, 0.012; ixz does not enter).  Then

      M(q) = Σ m J_Gᵀ J_G + Iyy₁ e₁e₁ᵀ + Iyy₂ (1,1)(1,1)ᵀ,   V = g Σ m z_G,
      joint springs K = diag(1500, 400) with zero torque at q_ref = (0.4, −0.8),
      dampers D = diag(0.5, 0.2) (<dynamics damping>),
      equilibrium K (q − q_ref) + ∇V = 0 (Newton), eigenvalues of M s² + D s + (K + ∇²V).
    """
    m1, m2, l1, a1, a2, I1, I2 = 2.0, 1.2, 0.4, 0.2, 0.15, 0.03, 0.012
    K, D, qref = np.diag([1500.0, 400.0]), np.diag([0.5, 0.2]), np.array([0.4, -0.8])

    def grad_hess_V(q):
        s1, c1, s12, c12 = math.sin(q[0]), math.cos(q[0]), math.sin(q.sum()), math.cos(q.sum())
        # z1 = 0.1 + a1 cos q1, z2 = 0.1 + l1 cos q1 + a2 cos(q1 + q2)
        dV = g * np.array([-m1 * a1 * s1 - m2 * (l1 * s1 + a2 * s12), -m2 * a2 * s12])
        h12 = -g * m2 * a2 * c12
        H = np.array([[-g * m1 * a1 * c1 - g * m2 * l1 * c1 + h12, h12], [h12, h12]])
        return dV, H

    q = qref.copy()
    for _ in range(50):
        dV, H = grad_hess_V(q)
        step = np.linalg.solve(K + H, K @ (q - qref) + dV)
        q -= step
        if np.max(np.abs(step)) < 1e-15:
            break

    def JG(q):  # x = Σ ℓ sin φ, z = Σ ℓ cos φ: Jacobians of (x, z) of each CoM
        s1, c1, s12, c12 = math.sin(q[0]), math.cos(q[0]), math.sin(q.sum()), math.cos(q.sum())
        J1 = np.array([[a1 * c1, 0.0], [-a1 * s1, 0.0]])
        J2 = np.array([[l1 * c1 + a2 * c12, a2 * c12], [-l1 * s1 - a2 * s12, -a2 * s12]])
        return J1, J2

    J1, J2 = JG(q)
    M = m1 * J1.T @ J1 + m2 * J2.T @ J2 + I1 * np.diag([1.0, 0.0]) + I2 * np.ones((2, 2))
    _, H = grad_hess_V(q)
    A = np.block([[np.zeros((2, 2)), np.eye(2)],
                  [-np.linalg.solve(M, K + H), -np.linalg.solve(M, D)]])
    s = np.linalg.eigvals(A)
    return np.sort_complex(s[s.imag > 0]), q


def test_two_link_arm_example_runs_and_matches_joint_space(capsys):
    """../shared/examples/two_link_arm.toml as written ([urdf] table): exit 0, and both modes
    within 1e-9 (relative) of :func:`arm_joint_space`."""
    if not ARM.exists():
        pytest.skip(f"{ARM} not there")
    code, out, err = cli(capsys, "modes", ARM, "--json")
    assert code == 0, err
    data = json.loads(out)
    got = sorted_upper([complex(*m["eigenvalue"]) for m in data["modes"]])
    ref, _ = arm_joint_space()
    assert data["dof"] == 2 and got.size == 2
    assert np.max(np.abs(got - ref) / np.abs(ref)) < 1e-9
    case = expand_urdf(tomllib.loads(ARM.read_text()), ARM)
    assert "urdf" not in case
    assert [b["name"] for b in case["bodies"]] == ["upper", "fore"]  # base → ground, tool merged
    assert [(j["type"], j["name"]) for j in case["joints"]] == [("revolute", "shoulder"),
                                                                ("revolute", "elbow")]


def test_two_link_arm_reference_pose_closed_form():
    """CoM of 'upper' = shoulder + 0.2 (sin 0.4, 0, cos 0.4); its inertia = R_y(0.4) I R_yᵀ."""
    case = expand_urdf(tomllib.loads(ARM.read_text()), ARM)
    upper = case["bodies"][0]
    c, s = math.cos(0.4), math.sin(0.4)
    assert np.allclose(upper["com"], [0.2 * s, 0.0, 0.1 + 0.2 * c], rtol=0, atol=1e-15)
    # diag(Ixx, Iyy, Izz) = (0.03, 0.03, 0.002) turned by θ about y (transformation of a
    # second-order tensor in the x-z plane): Ixx' = Ixx c² + Izz s², Izz' = Ixx s² + Izz c²,
    # Ixz' = (Izz − Ixx) s c
    Ixx, Izz = 0.03, 0.002
    expect = [[Ixx * c * c + Izz * s * s, 0.0, (Izz - Ixx) * s * c], [0.0, 0.03, 0.0],
              [(Izz - Ixx) * s * c, 0.0, Ixx * s * s + Izz * c * c]]
    assert np.allclose(upper["inertia"], expect, rtol=0, atol=1e-15)


def test_rpy_convention():
    """URDF rpy are fixed-axis X-Y-Z: yaw π/2 maps x → y, roll π/2 maps y → z, and
    R(r, p, y) = Rz(y) Ry(p) Rx(r) (URDF specification, <origin>)."""
    assert np.allclose(rpy_matrix([0, 0, math.pi / 2]) @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    assert np.allclose(rpy_matrix([math.pi / 2, 0, 0]) @ [0, 1, 0], [0, 0, 1], atol=1e-15)
    r, p, y = 0.3, -0.2, 0.5
    Rx = rpy_matrix([r, 0, 0])
    Ry = rpy_matrix([0, p, 0])
    Rz = rpy_matrix([0, 0, y])
    assert np.allclose(rpy_matrix([r, p, y]), Rz @ Ry @ Rx, atol=1e-15)


# ---------------------------------------------------------------------------------------------
# Small URDFs written in the tests
# ---------------------------------------------------------------------------------------------
def inertial(mass=1.0, xyz="0 0 0", rpy="0 0 0", i=("0.01", "0", "0", "0.01", "0", "0.01")):
    ixx, ixy, ixz, iyy, iyz, izz = i
    return (f'<inertial><origin xyz="{xyz}" rpy="{rpy}"/><mass value="{mass}"/>'
            f'<inertia ixx="{ixx}" ixy="{ixy}" ixz="{ixz}" iyy="{iyy}" iyz="{iyz}" izz="{izz}"/>'
            f'</inertial>')


def link(name, body=None):
    return f'<link name="{name}">{inertial() if body is None else body}</link>'


def joint(name, parent, child, kind="revolute", extra='<axis xyz="0 0 1"/>', xyz="0 0 0.1"):
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}"/>{extra}</joint>')


def write(tmp_path, *parts, name="r.urdf"):
    path = tmp_path / name
    path.write_text('<?xml version="1.0"?><robot name="r">' + "".join(parts) + "</robot>")
    return path


def tables(path, **options):
    return urdf_tables(read_urdf(path), **options)


def test_merging_massless_links(tmp_path):
    """world (massless root) → ground; 'flange' (massless, fixed) merges into a1; 'hub'
    (massless) moved by j2 hands the joint to 'arm2', fixed below it; 'tip' merges too."""
    path = write(tmp_path, '<link name="world"/>', link("a1"), '<link name="flange"/>',
                 '<link name="hub"/>', link("arm2"), '<link name="tip"/>',
                 joint("j1", "world", "a1"), joint("f1", "a1", "flange", "fixed", ""),
                 joint("j2", "flange", "hub", extra='<axis xyz="1 0 0"/>'),
                 joint("f2", "hub", "arm2", "fixed", ""), joint("f3", "arm2", "tip", "fixed", ""))
    t = tables(path)
    assert [b["name"] for b in t["bodies"]] == ["a1", "arm2"]
    assert [(j["name"], j["bodies"]) for j in t["joints"]] == [("j1", ["ground", "a1"]),
                                                               ("j2", ["a1", "arm2"])]
    assert t["joints"][1]["at"] == pytest.approx([0.0, 0.0, 0.3], abs=1e-15)
    # floating: 'world' is massless and a1 is moved by j1, not fixed to it: no mass to float
    with pytest.raises(CaseError, match=r"r\.urdf: link 'world': the floating root link"):
        tables(path, floating=True)


def test_massive_root_welded_or_free(tmp_path):
    path = write(tmp_path, link("base"), link("a"), joint("j", "base", "a"))
    fixed = tables(path)
    assert fixed["joints"][0] == {"type": "weld", "name": "base_to_ground",
                                  "bodies": ["ground", "base"], "at": [0.0, 0.0, 0.0]}
    free = tables(path, floating=True)
    assert [j["name"] for j in free["joints"]] == ["j"]


def test_springs_dampers_and_mimic_tables(tmp_path):
    path = write(tmp_path, link("base"), link("a"), link("b"), link("c"),
                 joint("j1", "base", "a", extra='<axis xyz="0 0 1"/><dynamics damping="0.3"/>'),
                 joint("s", "a", "b", "prismatic",
                       '<axis xyz="1 0 0"/><limit lower="-0.2" upper="0.5"/>'),
                 joint("m", "b", "c", extra='<axis xyz="0 0 1"/><mimic joint="j1" '
                       'multiplier="-0.5" offset="0.1"/>'))
    t = tables(path, positions={"j1": 0.4}, stiffness={"default": 10.0, "s": "k_s"},
               damping="urdf")
    forces = {f["name"]: f for f in t["forces"]}
    assert forces["j1_spring"] == {"type": "torsional", "name": "j1_spring", "joint": "j1",
                                   "stiffness": 10.0, "damping": 0.3}
    sp = forces["s_spring"]
    assert sp["type"] == "spring" and sp["stiffness"] == "k_s"
    a, b = np.array(sp["points"][0]["at"]), np.array(sp["points"][1]["at"])
    axis = np.array(next(j for j in t["joints"] if j["name"] == "s")["axis"])
    assert np.allclose(b - a, 1.5 * axis, atol=1e-15)  # ℓ = 1 + max |limit|, along the axis
    assert forces["m_spring"]["stiffness"] == 10.0  # the default reaches the follower too
    mim = next(j for j in t["joints"] if j["type"] == "mimic")
    assert mim == {"type": "mimic", "name": "m_mimic", "joint": "m", "leader": "j1",
                   "multiplier": -0.5}
    with pytest.raises(CaseError, match="contradicts its <mimic>"):
        tables(path, positions={"j1": 0.4, "m": 0.0})


BAD = {
    "no inertial carrying a joint": (
        lambda: ('<link name="base"/>', '<link name="a"/>', link("b"), joint("j", "base", "a"),
                 joint("k", "a", "b")),
        r"r\.urdf: link 'a': it has no <inertial> mass .* but joint 'j' moves it"),
    "not positive definite": (
        lambda: (link("base"), link("a", inertial(i=("0.01", "0", "0", "0.01", "0", "-0.001"))),
                 joint("j", "base", "a")),
        r"r\.urdf: link 'a' <inertia>: inertia tensor must be positive definite"),
    "triangle inequality": (
        lambda: (link("base"), link("a", inertial(i=("0.01", "0", "0", "0.01", "0", "0.03"))),
                 joint("j", "base", "a")),
        r"r\.urdf: link 'a' <inertia>: .* violate the triangle inequality"),
    "unknown joint type": (
        lambda: (link("base"), link("a"), joint("j", "base", "a", "screw")),
        r"r\.urdf: joint 'j': unsupported joint type 'screw'"),
    "two parents": (
        lambda: (link("base"), link("a"), link("b"), joint("j", "base", "a"),
                 joint("k", "b", "a")),
        r"r\.urdf: joint 'k': link 'a' has two parents"),
    "loop": (
        lambda: (link("base"), link("a"), link("b"), joint("j", "base", "a"),
                 joint("k", "a", "b"), joint("l", "b", "a")),
        r"r\.urdf: joint 'l': link 'a' has two parents .* kinematic loops"),
    "closed cycle": (
        lambda: (link("base"), link("a"), link("b"), joint("k", "a", "b"), joint("l", "b", "a")),
        r"r\.urdf: joint '[kl]': it closes a kinematic loop"),
    "missing link": (
        lambda: (link("base"), joint("j", "base", "ghost")),
        r"r\.urdf: joint 'j': <child> refers to the missing link 'ghost'"),
    "mimic of a missing joint": (
        lambda: (link("base"), link("a"),
                 joint("j", "base", "a", extra='<axis xyz="0 0 1"/><mimic joint="x"/>')),
        r"r\.urdf: joint 'j': <mimic> refers to 'x'"),
    "bad number": (
        lambda: (link("base"), link("a"), joint("j", "base", "a", xyz="0 0")),
        r"r\.urdf: joint 'j' <origin>: xyz='0 0' must be 3 finite numbers"),
    "several roots": (
        lambda: (link("base"), link("other")),
        r"r\.urdf: link 'other': the robot has several root links"),
    "malformed": (lambda: ("<link",), r"r\.urdf: malformed XML"),
}


@pytest.mark.parametrize("what", BAD)
def test_bad_urdf_messages(what, tmp_path):
    parts, message = BAD[what]
    path = write(tmp_path, *parts())
    with pytest.raises(CaseError, match=message) as exc:
        tables(path)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("what", ["no inertial carrying a joint", "not positive definite",
                                  "triangle inequality", "unknown joint type", "loop"])
def test_bad_urdf_from_the_cli(what, tmp_path, capsys):
    """The same errors through a case's [urdf] table and through import-urdf: one line
    ``mbseig: FILE: ELEMENT: problem``, exit 2, no traceback."""
    parts, message = BAD[what]
    path = write(tmp_path, *parts())
    case = tmp_path / "robot.toml"
    case.write_text('schema_version = 1\ndimension = 3\n[urdf]\nfile = "r.urdf"\n')
    for argv in (("modes", case, "--json"), ("import-urdf", path, "--out", tmp_path / "o.toml")):
        code, out, err = cli(capsys, *argv)
        assert code == 2 and out == ""
        assert err.count("\n") == 1 and err.startswith("mbseig: ") and "Traceback" not in err
        assert __import__("re").search(message, err), err


def test_case_table_errors(tmp_path):
    write(tmp_path, link("base"), link("a"), joint("j", "base", "a"))
    case = {"schema_version": 1, "dimension": 3, "urdf": {"file": "r.urdf"}}
    where = tmp_path / "c.toml"
    for table, message in [({"file": "r.urdf", "colour": 1}, "urdf: unknown field 'colour'"),
                           ({"file": "r.urdf", "positions": {"x": 1.0}}, "urdf: unknown joint 'x'"),
                           ({"file": "r.urdf", "positions": {"j": "a"}},
                            "j must be a finite number"),
                           ({"file": "r.urdf", "stiffness": {"j": -1.0}}, "stiffness.j must be"),
                           ({"file": "r.urdf", "damping": "pinocchio"}, "damping must be a table"),
                           ({"file": "r.urdf", "floating": 1}, "floating must be true or false"),
                           ({"file": "none.urdf"}, "none.urdf: cannot read URDF file")]:
        with pytest.raises(CaseError, match=message):
            expand_urdf({**case, "urdf": table}, where)
    with pytest.raises(CaseError, match=r"c\.toml: urdf: a case with \[urdf\] needs dimension = 3"):
        expand_urdf({**case, "dimension": 2}, where)


def test_own_entries_follow_the_robot_and_name_links(tmp_path, capsys):
    """The case's own forces come after the robot's and may name its links; import-urdf writes
    the plain case of the same model: identical `modes --json` eigenvalues (tolerance 0) and the
    joint-space reference of the arm (1e-9)."""
    case = tomllib.loads(ARM.read_text())
    case["forces"] = [{"type": "torque", "name": "push", "body": "fore", "vector": [0, 0.0, 0]}]
    out = expand_urdf(case, ARM)
    assert [f["name"] for f in out["forces"]] == ["shoulder_spring", "elbow_spring", "push"]
    written = tmp_path / "arm.toml"
    code, _, err = cli(capsys, "import-urdf", ARM.parent / "two_link_arm.urdf", "--out", written,
                       "--position", "shoulder=0.4", "--position", "elbow=-0.8",
                       "--stiffness", "default=400", "--stiffness", "shoulder=1500",
                       "--damping", "urdf")
    assert code == 0, err
    eig = {}
    for path in (ARM, written):
        code, text, err = cli(capsys, "modes", path, "--json")
        assert code == 0, err
        eig[path] = [m["eigenvalue"] for m in json.loads(text)["modes"]]
    assert eig[ARM] == eig[written]
    ref, _ = arm_joint_space()
    got = sorted_upper([complex(*e) for e in eig[written]])
    assert np.max(np.abs(got - ref) / np.abs(ref)) < 1e-9


# ---------------------------------------------------------------------------------------------
# Public robots against Pinocchio (tests/data/urdf/reference, see the module docstring)
# ---------------------------------------------------------------------------------------------
def reference(model):
    return json.loads((DATA / "reference" / f"{model}.json").read_text())


def urdf_of(ref, tmp_path):
    """The robot of a reference; the "nomimic" models read it without its <mimic> elements."""
    path = DATA / ref["urdf"].removeprefix("data/")
    if not ref["model"].endswith("_nomimic"):
        return path
    tree = ET.parse(path)
    for j in tree.getroot().findall("joint"):
        for m in j.findall("mimic"):
            j.remove(m)
    out = tmp_path / path.name
    tree.write(out)
    return out


def urdf_table(ref, variant, urdf):
    """The [urdf] table of a reference variant.  Springs k and dampers d on the reference's
    coordinates; a <mimic> follower (no coordinate of the reference) gets none (FOLLOWER = 0),
    except in the "allsprings" variants, where ``default`` reaches it as it reaches every
    moving joint (docs/urdf.md, "Springs on mimic joints")."""
    names = [c["name"] for c in ref["coordinates"]]
    table = {"file": str(urdf), "positions": dict(zip(names, ref["q0"], strict=True))}
    if variant.startswith("allsprings"):
        full = ref["mimic"]["full_joint_names"]
        table["stiffness"] = dict(zip(full, ref["allsprings_variant"]["k_full"], strict=True))
        table["damping"] = {"default": ref["d_uniform"][0]}
        return table
    followers = {j: 0.0 for j in (ref["mimic"] or {}).get("full_joint_names", []) if j not in names}
    table["stiffness"] = {**dict(zip(names, ref["k"], strict=True)), **followers}
    if variant.endswith("d_urdf"):
        table["damping"] = ({**dict(zip(names, ref["d_urdf"], strict=True)), **followers}
                            if followers else "urdf")
    else:
        table["damping"] = {**dict(zip(names, ref["d_uniform"], strict=True)), **followers}
    return table


def assert_matches(s, ref, variant, n_coordinates):
    """Every reference eigenvalue matched one to one by the nearest of mbseig's, relative 1e-9."""
    r = sorted_upper([complex(*x) for x in ref["cases"][variant]["eigenvalues"]])
    s = sorted_upper(s)
    assert s.size == r.size >= n_coordinates
    dist = np.abs(s[:, None] - r[None, :]) / np.abs(r)[None, :]
    assert len(set(dist.argmin(axis=0).tolist())) == r.size
    assert dist.min(axis=0).max() < 1e-9


REFS = [(m, v) for m in ("ur5", "panda")
        for v in ("no_gravity_d_uniform", "gravity_d_uniform", "no_gravity_d_urdf",
                  "gravity_d_urdf")]
REFS += [("panda", "allsprings_no_gravity_d_uniform"), ("panda", "allsprings_gravity_d_uniform"),
         ("panda_nomimic", "gravity_d_uniform"), ("toy", "gravity_d_uniform"),
         ("toy", "allsprings_gravity_d_uniform"), ("toy", "no_gravity_d_urdf"),
         ("toy_nomimic", "gravity_d_urdf")]


@pytest.mark.parametrize("model,variant", REFS, ids=[f"{m}-{v}" for m, v in REFS])
def test_pinocchio_reference(model, variant, tmp_path):
    """A case dict with an [urdf] table, read as a file would be (mbseig.read_case), against the
    reference eigenvalues (module docstring): relative 1e-9."""
    ref = reference(model)
    gravity = [0.0, 0.0, 0.0] if "no_gravity" in variant else ref["gravity"]
    case = {"schema_version": 1, "title": f"{model} {variant}", "dimension": 3,
            "gravity": gravity, "urdf": urdf_table(ref, variant, urdf_of(ref, tmp_path))}
    a = analyze(mbseig.read_case(case))
    assert_matches(a.modes.eigenvalues, ref, variant, len(ref["coordinates"]))


def test_import_urdf_writes_the_same_model(tmp_path, capsys):
    """`mbseig import-urdf` of the Panda (mimic fingers, fixed hand, products of inertia) with the
    reference's springs: its `modes --json` gives the Pinocchio eigenvalues (1e-9) and exactly
    those of the same robot read through [urdf] (tolerance 0: the same plain case)."""
    ref = reference("panda")
    table = urdf_table(ref, "gravity_d_uniform", DATA / "panda" / "panda.urdf")
    out = tmp_path / "panda.toml"
    argv = ["import-urdf", table["file"], "--out", out]
    for option, key in (("--position", "positions"), ("--stiffness", "stiffness"),
                        ("--damping", "damping")):
        argv += [a for name, v in table[key].items() for a in (option, f"{name}={v!r}")]
    code, text, err = cli(capsys, *argv)
    assert code == 0, err
    assert text.startswith(f"{out}: ")
    code, text, err = cli(capsys, "modes", out, "--json")
    assert code == 0, err
    written = [complex(*m["eigenvalue"]) for m in json.loads(text)["modes"]]
    assert_matches(written, ref, "gravity_d_uniform", len(ref["coordinates"]))
    case = {"schema_version": 1, "title": "panda", "dimension": 3,
            "gravity": [0.0, 0.0, -9.81], "urdf": table}
    direct = analyze(mbseig.read_case(case)).modes.eigenvalues
    assert np.array_equal(sorted_upper(direct), sorted_upper(written))
    assert tomllib.loads(out.read_text()) == tomllib.loads(to_toml(tomllib.loads(out.read_text())))
