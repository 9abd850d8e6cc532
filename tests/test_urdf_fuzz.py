"""Fuzzing the URDF input (issue 39): the bundled robots mutated by a seeded generator
(attributes, axes, deleted and duplicated elements, kinematic loops, truncation, huge, NaN,
negative and subnormal values, joint types), each variant read as a case reads it.  Every
variant must end in an answer (the model builds) or in one :class:`~mbseig.errors.CaseError`
line that names the URDF file and the link or joint (or the XML), with no Python warning
before it and no other exception.

The suite runs ``N_SUITE`` variants (a few seconds); ``python tests/test_urdf_fuzz.py N [SEED]``
runs N more by hand, through the command line too (``import-urdf`` then ``modes``), and prints
what they found.
"""

from __future__ import annotations

import random
import re
import sys
import warnings
from pathlib import Path

import pytest

import mbseig
from mbseig.casefile.urdf import read_urdf, urdf_tables
from mbseig.errors import MbseigError

DATA = Path(__file__).resolve().parent / "data" / "urdf"
# robots mutated (TALOS is left out: its file's own header licenses it without derivatives)
ROBOTS = [DATA / "ur5" / "ur5_robot.urdf", DATA / "panda" / "panda.urdf",
          DATA / "so101" / "so101.urdf", DATA / "toy" / "toy_rpm.urdf",
          DATA / "arm" / "two_link_arm.urdf"]
N_SUITE = 120
VALUES = ["1e308", "-1e308", "nan", "inf", "-inf", "-0.0", "0", "-1", "1e-320", "5e-324", "abc",
          "", "1 2", "1 2 3 4", "1e100", "1e101", "1e-101", "0x10", "1_000"]
AXES = ["0 0 0", "1e308 0 0", "1e-320 0 0", "nan 0 0", "0 0 -1", "1 1 1", "0.6 0.8", "1e100 1 0"]
TYPES = ["revolute", "continuous", "prismatic", "fixed", "planar", "floating", "bogus", ""]
NUMERIC = {"origin": ("xyz", "rpy"), "axis": ("xyz",), "mass": ("value",),
           "inertia": ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), "limit": ("lower", "upper"),
           "dynamics": ("damping",), "mimic": ("multiplier", "offset")}
TAGS = ["link", "joint", "inertial", "origin", "mass", "inertia", "axis", "parent", "child",
        "mimic", "limit"]


def _elements(text, tag):
    """(start, end) of each ``<tag ...>...</tag>`` or ``<tag .../>`` in the text."""
    out = []
    for m in re.finditer(rf"<{tag}[\s/>]", text):
        start = m.start()
        close = text.find(">", start)
        if close < 0:
            continue
        if text[close - 1] == "/":
            out.append((start, close + 1))
            continue
        end = text.find(f"</{tag}>", close)
        if end >= 0:
            out.append((start, end + len(tag) + 3))
    return out


def _names(text, tag):
    return re.findall(rf'<{tag}\s+name="([^"]*)"', text)


def mutate(text: str, rng: random.Random) -> tuple[str, str]:
    """One mutation of a URDF text: (new text, what was done)."""
    kind = rng.choice(["value", "value", "axis", "delete", "duplicate", "loop", "truncate",
                       "type", "attribute", "negative"])
    if kind in ("value", "negative"):
        tag = rng.choice(list(NUMERIC))
        spots = [m for m in re.finditer(rf"<{tag}\b[^>]*>", text)]
        if spots:
            m = rng.choice(spots)
            attr = rng.choice(NUMERIC[tag])
            el = m.group(0)
            value = "-1" if kind == "negative" else rng.choice(VALUES)
            if f'{attr}="' in el:
                new = re.sub(rf'\b{attr}="[^"]*"', f'{attr}="{value}"', el)
            else:
                new = el.replace(f"<{tag}", f'<{tag} {attr}="{value}"', 1)
            return text[:m.start()] + new + text[m.end():], f"<{tag} {attr}={value!r}>"
    if kind == "axis":
        spots = list(re.finditer(r'<axis\s+xyz="[^"]*"', text))
        if spots:
            m = rng.choice(spots)
            axis = rng.choice(AXES)
            return text[:m.start()] + f'<axis xyz="{axis}"' + text[m.end():], f"axis {axis!r}"
    if kind in ("delete", "duplicate"):
        tag = rng.choice(TAGS)
        spots = _elements(text, tag)
        if spots:
            a, b = rng.choice(spots)
            if kind == "delete":
                return text[:a] + text[b:], f"deleted a <{tag}>"
            return text[:b] + text[a:b] + text[b:], f"duplicated a <{tag}>"
    if kind == "loop":
        links = _names(text, "link")
        if len(links) >= 2:
            parent, child = rng.sample(links, 2)
            extra = (f'<joint name="fuzz_loop" type="revolute"><parent link="{parent}"/>'
                     f'<child link="{child}"/><axis xyz="0 0 1"/></joint>')
            k = text.rfind("</robot>")
            return text[:k] + extra + text[k:], f"a joint {parent} → {child}"
    if kind == "truncate":
        k = rng.randrange(len(text))
        return text[:k], f"truncated at {k}"
    if kind == "type":
        spots = list(re.finditer(r'(<joint\s+name="[^"]*"\s+type=")([^"]*)"', text))
        if spots:
            m = rng.choice(spots)
            t = rng.choice(TYPES)
            return text[:m.start()] + m.group(1) + t + '"' + text[m.end():], f"type {t!r}"
    if kind == "attribute":
        spots = list(re.finditer(r'\b(name|link|joint)="[^"]*"', text))
        if spots:
            m = rng.choice(spots)
            return text[:m.start()] + text[m.end():], f"removed {m.group(0)}"
    return text, "unchanged"


def variants(n, seed=39):
    """n mutated robots: (robot path, text, what was changed), one or two mutations each."""
    rng = random.Random(seed)
    texts = {p: p.read_text() for p in ROBOTS}
    for _ in range(n):
        path = rng.choice(ROBOTS)
        text, what = texts[path], []
        for _ in range(rng.choice((1, 1, 2))):
            text, w = mutate(text, rng)
            what.append(w)
        yield path, text, "; ".join(what)


def outcome(file: Path):
    """"answer" when the robot reads and its model builds, else the CaseError's line; anything
    else (another exception, a warning) raises AssertionError."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            robot = read_urdf(file)
            tables = urdf_tables(robot, stiffness={"default": 100.0})
            case = {"schema_version": 1, "dimension": 3, "gravity": [0.0, 0.0, -9.81],
                    **{k: v for k, v in tables.items() if v}}
            mbseig.read_case(case).build()
            return "answer"
        except MbseigError as exc:
            line = str(exc)
        except Exception as exc:  # noqa: BLE001 - the point of the test: no other exception
            raise AssertionError(f"{type(exc).__name__}: {exc}") from exc
    assert "\n" not in line, line
    assert line.startswith(f"{file}: "), line
    assert re.search(r"(link|joint) '|(link|joint): a <(link|joint)> without a name|"
                     r"malformed XML|xacro|robot: |no <link>|root element", line), line
    return line


@pytest.mark.parametrize("chunk", range(4))
def test_fuzzed_urdfs_answer_or_refuse_in_one_line(chunk, tmp_path):
    """N_SUITE variants (seed 39) in four chunks: each gives an answer or one line naming the
    file and the link or joint, never another exception or a warning."""
    items = list(variants(N_SUITE))[chunk::4]
    for k, (path, text, what) in enumerate(items):
        file = tmp_path / f"{path.stem}_{k}.urdf"
        file.write_text(text)
        try:
            outcome(file)
        except AssertionError as exc:
            raise AssertionError(f"{path.name} with {what}: {exc}") from None


def by_hand(n, seed):  # pragma: no cover - run by hand (module docstring)
    import collections
    import subprocess
    import tempfile

    counts, kinds = collections.Counter(), collections.Counter()
    with tempfile.TemporaryDirectory() as tmp:
        for k, (path, text, what) in enumerate(variants(n, seed)):
            file = Path(tmp) / f"{path.stem}_{k}.urdf"
            file.write_text(text)
            try:
                got = outcome(file)
            except AssertionError as exc:
                counts["FAILED"] += 1
                print(f"FAILED {path.name} with {what}: {exc}")
                continue
            counts["answer" if got == "answer" else "refused"] += 1
            if got != "answer":
                kinds[re.sub(r"'[^']*'|\S+=\S+|[-\d.e+]{3,}", "…", got.split(": ", 1)[1])[:70]] += 1
            if k % 10 == 0:  # the command line too: import-urdf, then modes (exit 0 or 2)
                case = Path(tmp) / "c.toml"
                for argv in (["import-urdf", str(file), "--out", str(case), "--stiffness",
                              "default=500", "--damping", "default=0.5"],
                             ["modes", str(case), "--json"]):
                    r = subprocess.run([sys.executable, "-W", "error", "-m", "mbseig", *argv],
                                       capture_output=True, text=True)
                    if r.returncode not in (0, 2) or (r.returncode == 2 and (
                            r.stderr.count("\n") != 1 or not r.stderr.startswith("mbseig: "))):
                        counts["CLI FAILED"] += 1
                        print(f"CLI FAILED {path.name} with {what}: {argv[0]} exit "
                              f"{r.returncode}: {r.stderr[-500:]}")
                    if r.returncode:
                        break
                counts["cli runs"] += 1
    print(dict(counts))
    for text, c in kinds.most_common(40):
        print(f"{c:5d}  {text}")


if __name__ == "__main__":
    by_hand(int(sys.argv[1]), int(sys.argv[2]) if len(sys.argv) > 2 else 1)
