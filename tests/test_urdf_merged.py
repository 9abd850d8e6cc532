"""Robots as Pinocchio reads them (issue 39): fixed-joint links merged into their parent, point
masses on fixed joints, merged links addressable as frames, planar and floating joints, xacro
refused with the command that expands it, and the note after an import without springs.

References and tolerances:
- TALOS left arm and SO-101 (tests/data/urdf/{talos,so101}, example-robot-data 6.0.0) against
  Pinocchio 4.1 (reference/<model>.json, compute_reference.py): the joints, the merged body of
  each joint (mass, centre, inertia) and the joint of every link frame; the eigenvalues of
  M(q*) s² + D s + (K + ∂g/∂q) to 1e-8 relative.  That tolerance is a first-order perturbation
  bound: the two programs compute the same exact model by different sums, so their matrices
  differ by a relative δ of a modest multiple of the unit round-off u = 1.1e-16; an eigenvalue
  then moves by at most κ·δ relative, κ its normwise condition number (Tisseur 2000, stored
  in the JSON, at most 1.2e3 here).  1e-8 covers δ = 5e-12 (≈ 4.5e4 u), asserted as κ·5e-12 ≤
  1e-8 before the comparison.
- merged inertias: sums of at most a dozen products of rotation entries (≤ 1) and URDF values
  along chains of at most 8 frames, so each path's rounding is below 8·3·3·u ≈ 1.6e-14 of the
  largest term: 1e-13 of the largest entry;
- closed forms named in each test (reduced mass, decoupled springs).
"""

from __future__ import annotations

import json
import random
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from test_urdf import DATA, cli, inertial, joint, link, reference, sorted_upper, urdf_table, write
from test_urdf_fuzz import mutate

import mbseig
from mbseig.casefile.urdf import read_urdf, urdf_tables
from mbseig.errors import CaseError
from mbseig.studies import analyze

MERGED = {"talos_left_arm": DATA / "talos" / "talos_left_arm.urdf",
          "so101": DATA / "so101" / "so101.urdf"}
VARIANTS = ("no_gravity_d_uniform", "gravity_d_uniform", "no_gravity_d_urdf", "gravity_d_urdf")
REPRO = Path(__file__).resolve().parents[2] / "shared" / "repro" / "urdf"
DELTA, TOL = 5e-12, 1e-8  # data perturbation covered, eigenvalue tolerance (module docstring)


def case_of(model, variant):
    ref = reference(model)
    gravity = [0.0, 0.0, 0.0] if "no_gravity" in variant else ref["gravity"]
    return ref, {"schema_version": 1, "title": f"{model} {variant}", "dimension": 3,
                 "gravity": gravity, "urdf": urdf_table(ref, variant, MERGED[model])}


def assert_close(s, ref, variant):
    """Every reference eigenvalue matched one to one by mbseig's nearest, relative TOL, once the
    condition numbers show that TOL covers a perturbation DELTA of the matrices."""
    c = ref["cases"][variant]
    assert max(c["condition"]) * DELTA <= TOL
    r = sorted_upper([complex(*x) for x in c["eigenvalues"]])
    s = sorted_upper(s)
    assert s.size == r.size >= len(ref["coordinates"])
    dist = np.abs(s[:, None] - r[None, :]) / np.abs(r)[None, :]
    assert len(set(dist.argmin(axis=0).tolist())) == r.size
    assert dist.min(axis=0).max() <= TOL


@pytest.mark.parametrize("model,variant", [(m, v) for m in MERGED for v in VARIANTS])
def test_point_mass_robots_match_pinocchio(model, variant):
    ref, case = case_of(model, variant)
    a = analyze(mbseig.read_case(case))
    assert_close(a.modes.eigenvalues, ref, variant)


@pytest.mark.parametrize("model", MERGED)
def test_same_joints_merged_inertias_and_link_frames(model):
    """The moving joints are Pinocchio's; the body each moves has Pinocchio's merged mass,
    centre and inertia; every link is the body of the joint Pinocchio hangs its frame on."""
    ref = reference(model)
    names = [c["name"] for c in ref["coordinates"]]
    t = urdf_tables(read_urdf(MERGED[model]), positions=dict(zip(names, ref["q0"], strict=True)))
    moved = {j["name"]: j["bodies"][1] for j in t["joints"] if j["type"] == "revolute"}
    assert sorted(moved) == sorted(names)
    bodies = {b["name"]: b for b in t["bodies"]}
    for pb in ref["merged_bodies_at_q0"]:
        b = bodies[moved[pb["joint"]]]
        scale = np.max(np.abs(pb["inertia"]))
        assert abs(b["mass"] - pb["mass"]) <= 1e-13 * pb["mass"]
        assert (np.max(np.abs(np.subtract(b["com"], pb["com"])))
                <= 1e-13 * max(1.0, np.max(np.abs(pb["com"]))))
        assert np.max(np.abs(np.subtract(b["inertia"], pb["inertia"]))) <= 1e-13 * scale
    root = next(j["bodies"][1] for j in t["joints"] if j["type"] == "weld")
    body_of = {**{n: n for n in bodies}, **{f["name"]: f["body"] for f in t["frames"]}}
    for frame, pjoint in ref["frame_joint"].items():
        assert body_of[frame] == (root if pjoint == "universe" else moved[pjoint]), frame
    point_masses = [n for n, link in read_urdf(MERGED[model]).links.items()
                    if link.mass > 0 and not np.any(link.inertia)]
    assert point_masses and all(n not in bodies for n in point_masses)  # merged, not bodies


def test_talos_through_the_command_line(tmp_path, capsys):
    """As a new user would: import-urdf with springs, then modes --json: exit 0, no output on
    stderr, Pinocchio's eigenvalues (TOL)."""
    ref = reference("talos_left_arm")
    out = tmp_path / "talos.toml"
    argv = ["import-urdf", MERGED["talos_left_arm"], "--out", out, "--stiffness", "default=300",
            "--damping", "default=2"]
    argv += [a for n, q in zip([c["name"] for c in ref["coordinates"]], ref["q0"], strict=True)
             for a in ("--position", f"{n}={q!r}")]
    code, text, err = cli(capsys, *argv)
    assert code == 0 and err == "" and "note:" not in text
    code, text, err = cli(capsys, "modes", out, "--json")
    assert code == 0 and err == ""
    s = [complex(*m["eigenvalue"]) for m in json.loads(text)["modes"]]
    assert_close(s, ref, "gravity_d_uniform")


def test_point_mass_merged_in_closed_form(tmp_path):
    """A 0.5 kg point mass (zero inertia) fixed 0.2 m along x from a 1 kg body with I = 0.01 E:
    m = 1.5, c = 0.2·0.5/1.5, I_yy = I_zz = 0.01 + μ d² with the reduced mass μ = 1·0.5/1.5,
    I_xx = 0.01 (parallel-axis theorem)."""
    point = inertial(0.5, i=("0", "0", "0", "0", "0", "0"))
    path = write(tmp_path, '<link name="base"/>', link("a"), f'<link name="p">{point}</link>',
                 joint("j", "base", "a", xyz="0 0 0"),
                 joint("f", "a", "p", "fixed", "", xyz="0.2 0 0"))
    t = urdf_tables(read_urdf(path))
    (b,) = t["bodies"]
    assert b["name"] == "a" and b["mass"] == 1.5
    assert np.allclose(b["com"], [0.2 * 0.5 / 1.5, 0, 0], rtol=0, atol=1e-16)
    Iyy = 0.01 + (0.5 / 1.5) * 0.2 ** 2
    assert np.allclose(b["inertia"], np.diag([0.01, Iyy, Iyy]), rtol=0, atol=1e-16)
    assert t["frames"] == [{"name": "base", "body": "ground"}, {"name": "p", "body": "a"}]


def test_singular_merged_inertia_names_body_and_links(tmp_path):
    """Two point masses on one moving body lie on a line: no inertia about it.  Refused in one
    line naming the body and the link merged into it; a point mass alone likewise."""
    point = inertial(0.1, i=("0", "0", "0", "0", "0", "0"))
    path = write(tmp_path, '<link name="base"/>', f'<link name="p">{point}</link>',
                 f'<link name="q">{point}</link>', joint("j", "base", "p"),
                 joint("f", "p", "q", "fixed", "", xyz="0.3 0 0"))
    with pytest.raises(CaseError, match=r"r\.urdf: link 'p': its inertia merged with the links "
                       r"fixed to it \('q'\): inertia tensor must be positive definite"):
        urdf_tables(read_urdf(path))
    alone = write(tmp_path, '<link name="base"/>', f'<link name="p">{point}</link>',
                  joint("j", "base", "p"), name="alone.urdf")
    with pytest.raises(CaseError, match=r"alone\.urdf: link 'p' <inertia>: inertia tensor must "
                       r"be positive definite \(principal moments 0, 0, 0\)"):
        urdf_tables(read_urdf(alone))


# ---------------------------------------------------------------------------------------------
# Merged links stay addressable (DESIGN §8: link names are body names for the rest of the case)
# ---------------------------------------------------------------------------------------------
ARM_URDF = DATA / "arm" / "two_link_arm.urdf"


def arm_case(forces=(), joints=()):
    return {"schema_version": 1, "dimension": 3, "gravity": [0.0, 0.0, -9.81],
            "urdf": {"file": str(ARM_URDF), "positions": {"shoulder": 0.4, "elbow": -0.8},
                     "stiffness": {"default": 400.0}},
            "forces": list(forces), "joints": list(joints)}


def test_merged_links_are_frames_of_their_body():
    """'tool' (merged into 'fore') and 'base' (the fixed root, merged into the ground) name
    frames: a force, a torque and a bushing written on them give exactly the model written on
    'fore' and 'ground' (tolerance 0: the same arithmetic)."""
    def elements(tool, base):
        return [{"type": "force", "name": "load", "point": {"body": tool, "at": [0.1, 0.0, 0.9]},
                 "vector": [0.0, 0.0, -5.0]},
                {"type": "torque", "name": "twist", "body": tool, "vector": [0.0, 0.3, 0.0]},
                {"type": "bushing", "name": "stay", "bodies": [base, tool], "at": [0.1, 0, 0.9],
                 "stiffness": [50.0, 50.0, 50.0, 1.0, 1.0, 1.0]}]

    s = [analyze(mbseig.read_case(arm_case(elements(*names)))).modes.eigenvalues
         for names in (("tool", "base"), ("fore", "ground"))]
    assert np.array_equal(s[0], s[1])
    plain = analyze(mbseig.read_case(arm_case())).modes.eigenvalues
    assert not np.allclose(np.sort_complex(s[0]), np.sort_complex(plain))  # the elements act


def test_frame_errors(tmp_path, capsys):
    bad = arm_case([{"type": "torque", "name": "t", "body": "base", "vector": [0, 1.0, 0]}])
    with pytest.raises(CaseError, match=r"forces\[2\] 't': 'base' is a frame of the ground"):
        mbseig.read_case(bad).build()
    for frames, message in [([{"name": "x", "body": "nope"}], r"frames\[\d\] 'x': unknown body"),
                            ([{"name": "fore", "body": "upper"}], "is a body's or another"),
                            ({"name": "x"}, "frames must be an array of tables")]:
        case = {**arm_case(), "frames": frames}
        with pytest.raises(CaseError, match=message):
            mbseig.read_case(case).build()
    planar = {"schema_version": 1, "dimension": 2, "frames": [{"name": "x", "body": "b"}]}
    with pytest.raises(CaseError, match=r"frames: \[\[frames\]\] names frames of 3-D bodies"):
        mbseig.read_case(planar).build()
    written = tmp_path / "arm.toml"
    code, out, err = cli(capsys, "import-urdf", ARM_URDF, "--out", written, "--stiffness",
                         "default=400")
    assert code == 0 and '[[frames]]\nname = "tool"\nbody = "fore"' in written.read_text()


# ---------------------------------------------------------------------------------------------
# Planar and floating joints
# ---------------------------------------------------------------------------------------------
def test_planar_joint_keeps_the_in_plane_motions(tmp_path):
    """A 2 kg body (I = diag(0.1, 0.2, 0.25)) on a planar joint of normal y, held at its centre
    of mass by a bushing k = (100, 200, 300, 4, 5, 6), no gravity: the joint leaves x, z and the
    turn about y, so ω² = 100/2, 300/2, 5/0.2 (decoupled springs), 3 degrees of freedom."""
    body = inertial(2.0, i=("0.1", "0", "0", "0.2", "0", "0.25"))
    path = write(tmp_path, '<link name="base"/>', f'<link name="a">{body}</link>',
                 joint("j", "base", "a", "planar", '<axis xyz="0 1 0"/>', xyz="0 0 0.5"))
    case = {"schema_version": 1, "dimension": 3, "gravity": [0.0, 0.0, 0.0],
            "urdf": {"file": str(path)},
            "forces": [{"type": "bushing", "name": "hold", "bodies": ["ground", "a"],
                        "at": [0.0, 0.0, 0.5], "stiffness": [100.0, 200.0, 300.0, 4.0, 5.0, 6.0]}]}
    a = analyze(mbseig.read_case(case))
    assert a.linear.dof == 3
    got = np.sort(np.abs(sorted_upper(a.modes.eigenvalues)))
    assert np.allclose(got, np.sqrt([25.0, 50.0, 150.0]), rtol=1e-9, atol=0)
    with pytest.raises(CaseError, match=r"stiffness: 'j' is a planar joint"):
        urdf_tables(read_urdf(path), stiffness={"j": 1.0})


def test_floating_joint_is_a_free_base(tmp_path):
    """world → base by a floating joint reads as the robot without 'world' and floating = true
    (the same bodies, joints and springs); floating = true on top of it is refused, saying so."""
    arm = (link("base"), link("a"), joint("j", "base", "a", extra='<axis xyz="0 1 0"/>'))
    free = write(tmp_path, '<link name="world"/>', *arm,
                 '<joint name="w" type="floating"><parent link="world"/><child link="base"/>'
                 '</joint>', name="free.urdf")
    plain = write(tmp_path, *arm, name="plain.urdf")
    a = urdf_tables(read_urdf(free), stiffness={"default": 10.0})
    b = urdf_tables(read_urdf(plain), stiffness={"default": 10.0}, floating=True)
    assert {k: a[k] for k in ("bodies", "joints", "forces")} == \
        {k: b[k] for k in ("bodies", "joints", "forces")}
    assert a["frames"] == [{"name": "world", "body": "ground"}]
    with pytest.raises(CaseError, match=r"link 'world': the floating root link .* its joint "
                       r"'w' is floating already"):
        urdf_tables(read_urdf(free), floating=True)


def test_link_names_the_case_cannot_hold(tmp_path):
    """Public robots name links 'ground' (asr_twodof) or 'link_8.0' (Allegro hand): refused in
    one line naming the link, not left to the case reader."""
    for name, why in (("ground", "'ground' names the case's fixed frame"),
                      ("link_8.0", "'.' separates beam stations")):
        path = write(tmp_path, link("base"), link(name), joint("j", "base", name))
        with pytest.raises(CaseError, match=rf"r\.urdf: link '{re.escape(name)}': the link's "
                           rf"name cannot be a name of the case \({why}"):
            urdf_tables(read_urdf(path))


def test_mimic_leader_later_in_the_tree(tmp_path):
    """A follower whose leader comes later in breadth-first order (TIAGo Pro's gripper): the
    mimic joints follow every joint, so the case reads."""
    follower = '<axis xyz="0 0 1"/><mimic joint="late" multiplier="0.5"/>'
    path = write(tmp_path, link("base"), link("a"), link("b"), link("c"),
                 joint("early", "base", "a", extra=follower), joint("mid", "base", "b"),
                 joint("late", "b", "c"))
    t = urdf_tables(read_urdf(path), stiffness={"default": 10.0})
    assert [j["name"] for j in t["joints"]][-1] == "early_mimic"
    case = {"schema_version": 1, "dimension": 3, "gravity": [0.0, 0.0, 0.0], **t}
    assert mbseig.read_case(case).build().n > 0


# ---------------------------------------------------------------------------------------------
# xacro, and the note after an import without springs
# ---------------------------------------------------------------------------------------------
XACRO = ('<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">'
         '<xacro:macro name="arm" params="n"><link name="${n}"/></xacro:macro>'
         '<link name="base"/><xacro:arm n="upper"/></robot>')


@pytest.mark.parametrize("name,text,what", [
    ("r.urdf.xacro", XACRO, "<xacro:macro>"),
    ("r.xacro", XACRO.replace(' xmlns:xacro="http://www.ros.org/wiki/xacro"', ""),
     "<xacro:...> elements"),
    ("r.xacro", '<robot name="r"><link name="${prefix}base"/></robot>', "the substitution")])
def test_xacro_is_refused_with_the_command(name, text, what, tmp_path, capsys):
    path = tmp_path / name
    path.write_text(text)
    code, out, err = cli(capsys, "import-urdf", path, "--out", tmp_path / "o.toml")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith(f"mbseig: {path}: the file still holds xacro markup ({what}")
    assert f"`xacro {name} > robot.urdf`" in err


def test_expanded_xacro_file_reads(tmp_path):
    """A .xacro holding plain URDF (the xacro namespace declared, as expanded files keep it)."""
    path = tmp_path / "r.urdf.xacro"
    path.write_text(XACRO.split("<xacro:macro")[0] + link("base") + link("a")
                    + joint("j", "base", "a") + "</robot>")
    assert [b["name"] for b in urdf_tables(read_urdf(path))["bodies"]] == ["base", "a"]


def test_note_after_an_import_without_springs(tmp_path, capsys):
    """The two-link arm upright without springs: the note on stdout says what the statics found
    and how to get a stable rest position; exit 0, nothing on stderr."""
    code, out, err = cli(capsys, "import-urdf", ARM_URDF, "--out", tmp_path / "a.toml")
    assert code == 0 and err == ""
    note = out.splitlines()[1]
    assert note.startswith("note: no joint springs (--stiffness)")
    assert "the equilibrium found is statically unstable, 2 direction(s)" in note
    for hint in ("--stiffness default=K", "--damping default=C", "stable_alternative",
                 "--position JOINT=VALUE"):
        assert hint in note
    code, out, err = cli(capsys, "import-urdf", ARM_URDF, "--out", tmp_path / "b.toml",
                         "--no-gravity")
    assert code == 0 and "there is no gravity" in out and err == ""


# ---------------------------------------------------------------------------------------------
# The issue's failing inputs: the shared files where present, and the same changes made here
# ---------------------------------------------------------------------------------------------
def changed(text, rng_seed, pattern, new):
    """The text with the first match of ``pattern`` replaced (a deterministic edit)."""
    out, n = re.subn(pattern, new, text, count=1)
    assert n == 1, pattern
    return out


UR5 = (DATA / "ur5" / "ur5_robot.urdf").read_text()
EDITS = {
    "inertia entry 1e308": changed(UR5, 0, r'iyy="[^"]*"', 'iyy="1e308"'),
    "axis 1e308 0 0": changed(UR5, 0, r'<axis xyz="[^"]*"', '<axis xyz="1e308 0 0"'),
    "planar joint": changed(UR5, 0, r'type="revolute"', 'type="planar"'),
    "bogus type": changed(UR5, 0, r'type="revolute"', 'type="bogus"'),
    "ixx -0.0": changed(UR5, 0, r'ixx="[^"]*"', 'ixx="-0.0"'),
    "fixed joint deleted": re.sub(r'<joint name="world_joint".*?</joint>', "", UR5, flags=re.S),
}


def run_cli_strict(capsys, *argv):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return cli(capsys, *argv)


def one_line_or_answer(capsys, path, tmp_path):
    out_case = tmp_path / "c.toml"
    code, out, err = run_cli_strict(capsys, "import-urdf", path, "--out", out_case,
                                    "--stiffness", "default=500", "--damping", "default=0.5")
    assert code in (0, 2), err
    if code == 2:
        assert out == "" and err.count("\n") == 1 and err.startswith(f"mbseig: {path}: ")
        return err
    code, out, err = run_cli_strict(capsys, "modes", out_case, "--json")
    assert code in (0, 2) and (code == 0 or err.count("\n") == 1), err
    return "answer" if code == 0 else err


@pytest.mark.parametrize("what", EDITS)
def test_issue_edits_answer_or_one_line(what, tmp_path, capsys):
    path = tmp_path / "ur5.urdf"
    path.write_text(EDITS[what])
    got = one_line_or_answer(capsys, path, tmp_path)
    expect = {"inertia entry 1e308": "<inertia>: iyy='1e308' is out of range",
              "axis 1e308 0 0": "<axis>: xyz='1e308 0 0' is out of range",
              "planar joint": "answer",
              "bogus type": "unsupported joint type 'bogus'",
              "ixx -0.0": "inertia tensor must be positive definite",
              "fixed joint deleted": "the robot has several root links"}[what]
    assert expect in got


@pytest.mark.skipif(not REPRO.is_dir(), reason="the shared repro files are not beside the checkout")
@pytest.mark.parametrize("name", ["kinova_008", "kinova_295", "z1_072", "z1_118", "z1_126",
                                  "z1_255", "z1_326"])
def test_shared_repro_files(name, tmp_path, capsys):
    one_line_or_answer(capsys, REPRO / f"{name}.urdf", tmp_path)


def test_mutator_changes_the_text():
    """The fuzzer's mutations change the robot (a fuzz test of unchanged files tests nothing)."""
    rng = random.Random(0)
    text = ARM_URDF.read_text()
    changed_texts = [mutate(text, rng) for _ in range(50)]
    assert sum(t != text for t, _ in changed_texts) >= 40
