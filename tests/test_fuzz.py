"""Fuzz suite (issue 17): mutated inputs through the CLI entry point, in process.

Hypothesis strategies mutate the bundled cases (``cases/*.toml``) as text (values replaced,
keys renamed or duplicated, lines deleted or duplicated, tables duplicated, files truncated or
given invalid bytes) and as parsed data (a value anywhere in the TOML tree replaced by a
hostile number, string, list or table; keys deleted or added; array entries duplicated), mutate
the command line (``--param`` overrides, options), and mutate the ``.npz`` matrices of a linear
case (complex, huge, tiny, non-square, integer, object-typed, empty, truncated, missing key).
Every example runs ``mbseig.cli.main`` in a fresh temporary folder (the working directory) and
must keep the exit contract:

- 0: stdout is valid strict JSON (for ``--json``) with finite numbers, a listing that is not
  empty and accounts for every degree of freedom, and no warning at all;
- 2: exactly one line on stderr, starting ``mbseig: ``, and nothing else;
- 1: only from ``mbseig check`` (a mode failed);
- never a traceback, a leaked warning, a hang, or a file written outside the temporary folder.

A failure in this part of the code fails the test at once (Hypothesis shrinks it).  A failure
whose root cause lies in code worked on under other issues (AREAS: the eigensolvers and the
matrix reader, the statics, the spatial reader) is counted and the test reports it as an xfail
naming the area and the first example; tests/test_input_rules.py holds their reproductions.

Profiles: the default (CI) runs 190 derandomized examples in about 12 s;
``MBSEIG_FUZZ_EXAMPLES=10000`` runs that many in total (split over the strategies below).
With ``MBSEIG_FUZZ_REPORT=FILE`` every outcome is counted and written to FILE as JSON, and the
failures are collected instead of stopping at the first (for the long profile's report).
"""

from __future__ import annotations

import contextlib
import copy
import io
import json
import math
import os
import re
import shutil
import signal
import sys
import tempfile
import tomllib
import traceback
import warnings
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from conftest import CASES
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mbseig.cli import main

pytestmark = pytest.mark.filterwarnings("error")

TOTAL = int(os.environ.get("MBSEIG_FUZZ_EXAMPLES", "0") or 0)
REPORT = os.environ.get("MBSEIG_FUZZ_REPORT")
SHARE = {"text": 0.3, "data": 0.35, "args": 0.2, "npz": 0.15}
SHORT = {"text": 55, "data": 65, "args": 40, "npz": 30}  # the CI profile (≈ 12 s on 2 cores)
TIMEOUT = 60  # seconds per example: longer is a hang

CASE_TEXT = {p.name: p.read_text() for p in sorted(CASES.glob("*.toml"))}
CASE_DATA = {k: tomllib.loads(v) for k, v in CASE_TEXT.items()}
ROOT = CASES.parent

# ---------------------------------------------------------------------------------------------
# hostile values
# ---------------------------------------------------------------------------------------------
NUMBERS = [1e308, -1e308, 1.797e308, 1e300, -1e300, 1e-320, 5e-324, -5e-324, 0.0, -0.0, -1.0,
           1e-300, 1e30, -1e30, 1e-30, 1e15, 3.5, 0.5, 2.0, 1e100, 1e-100, 1e101, 1e-101,
           1e99, -1e99, 1e-99, 1e50, -1e50, 1e-50,
           math.nan, math.inf, -math.inf, 0, 1, -1, 2, 3, 7, 2**53 + 1, 10**18, -(10**18)]
STRINGS = ["", "x", "1e999", "nan", "inf", "-inf", "1/0", "__import__('os').system('echo hi')",
           "(1).__class__", "10**10**10", "exp(1000)", "sqrt(-1)", "9" * 400, "{", "}", "a.b",
           "m{i}", "1e308*10", "log(0)", "deg(1e308)", "n", "-n", "2**1023", "2**1024", "1e-320",
           "5e-324", "max()", "sqrt()", "atan2(1)", "min(1e308, -1e308)*2", "tan(pi/2)",
           "1e308+1e308", "0*inf", "g", "-g", "1e300*1e300", "1e-200*1e-200", "2*n", "n*1e300",
           "auto", "free", "clamped", "ground", "crank", "timoshenko", "circle", "O", "A", "B",
           "spring", "distance", "angle_driver", "x\x00y", "é", "1e308", "-1e308", "i", "{i}",
           "1e-320*1e-10", "abs(-1e308)", "pi", "e", "1e16", "0.1", "-0.1"]
OTHERS = [True, False, [], [1.0], [1.0, 2.0], [1.0, 2.0, 3.0], ["a", "b"], ["O", "O"], [[1.0]],
          [[1.0, 0.0], [0.0, 1.0]], [1e308, 1e308], [math.nan, 0.0], {}, {"a": 1},
          {"file": "x.npz"}, {"i": [1, 1e300]}, {"i": [1e300, 1e300]}, {"i": [0, "1e300"]},
          {"shape": "circle", "d": 1e-320}, {"body": "crank", "local": [1e308, 0.0]}]
# copies: a drawn list or table is mutated further and must not change the pool
VALUES = (st.sampled_from(NUMBERS) | st.sampled_from(STRINGS)
          | st.sampled_from(OTHERS).map(copy.deepcopy))


def toml_value(v) -> str:
    """A TOML inline value (floats by repr, so nan/inf and subnormals survive)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return {"nan": "nan", "inf": "inf", "-inf": "-inf"}.get(repr(v), repr(v))
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{toml_key(k)} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(type(v))


def toml_key(k) -> str:
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)


def dump_toml(data: dict) -> str:
    return "".join(f"{toml_key(k)} = {toml_value(v)}\n" for k, v in data.items())


# ---------------------------------------------------------------------------------------------
# the exit contract
# ---------------------------------------------------------------------------------------------
class _Hang(BaseException):
    """The example ran out of time; ``stack``: where it was (the mbseig frames)."""

    def __init__(self, stack):
        super().__init__("hang")
        self.stack = stack


def _alarm(signum, frame):
    raise _Hang([f'File "{f.filename}", line {f.lineno}' for f in traceback.extract_stack(frame)
                 if "/mbseig/" in f.filename])


def run_cli(argv, files: dict, workdir: Path) -> dict:
    """Run ``main(argv)`` in a fresh folder holding ``files``; the outcome as a dict."""
    folder = Path(tempfile.mkdtemp(dir=workdir))
    for name, content in files.items():
        (folder / name).write_bytes(content if isinstance(content, bytes) else content.encode())
    out, err = io.StringIO(), io.StringIO()
    old = os.getcwd()
    exc_text, code = None, None
    os.chdir(folder)
    fd_out = tempfile.TemporaryFile()  # what C code (LAPACK messages) writes to file descriptor 1
    sys.stdout.flush()
    saved_fd = os.dup(1)
    os.dup2(fd_out.fileno(), 1)
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(TIMEOUT)
    caught = []

    def keep(message, category, filename, lineno, file=None, line=None):
        stack = [f"{Path(fr.filename).as_posix()}:{fr.lineno}" for fr in traceback.extract_stack()]
        caught.append((f"{Path(filename).name}:{lineno}: {category.__name__}: {message}",
                       [f for f in stack if "/mbseig/" in f], category.__module__))

    try:
        with warnings.catch_warnings(), \
                contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            warnings.simplefilter("always")
            warnings.showwarning = keep
            try:
                code = main(argv)
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 2
            except _Hang as hang:
                code = "hang"
                exc_text = "\n".join(hang.stack)
            except Exception:  # noqa: BLE001 - a traceback is what the fuzz looks for
                exc_text = traceback.format_exc()
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
        os.dup2(saved_fd, 1)
        os.close(saved_fd)
        fd_out.seek(0)
        fd_text = fd_out.read().decode(errors="replace")
        fd_out.close()
        os.chdir(old)
        shutil.rmtree(folder, ignore_errors=True)
    return {"argv": argv, "code": code, "stdout": out.getvalue(), "stderr": err.getvalue(),
            "traceback": exc_text, "fd_stdout": fd_text,
            "warnings": [w[0] for w in caught], "warning_stacks": [w[1] for w in caught],
            "warning_modules": [w[2] for w in caught]}


def _strict_json(text):
    def bad(name):
        raise ValueError(f"non-finite JSON constant {name}")
    return json.loads(text, parse_constant=bad)


def _finite_numbers(obj, path=""):
    """Paths of null or non-finite numbers in a JSON value (where numbers belong)."""
    if obj is None:
        return [path]
    if isinstance(obj, float):
        return [] if math.isfinite(obj) else [path]
    if isinstance(obj, list):
        return [p for k, v in enumerate(obj) for p in _finite_numbers(v, f"{path}[{k}]")]
    if isinstance(obj, dict):
        return [p for k, v in obj.items() for p in _finite_numbers(v, f"{path}.{k}")]
    return []


MODE_NUMBERS = ("eigenvalue", "delta", "omega_n", "omega_d", "freq_hz", "zeta", "backward_error",
                "condition", "tolerance")


def _listing_problems(out, partial):
    probs = []
    # a periodic case's partial (Arnoldi) multipliers carry bounds but no condition number
    keys = [k for k in MODE_NUMBERS if not (k == "condition" and "partial" in (
        out.get("floquet") or {}))]
    for m in out.get("modes", []):
        # κ = ∞ (JSON null) is the true condition number of an eigenvalue in a Jordan block
        # (README, "Solver paths"): allowed there, with a finite cluster tolerance
        jordan = (m.get("multiplicity") or 1) >= 2 and m.get("condition", 0) is None
        bad = _finite_numbers({k: m.get(k) for k in keys if not (jordan and k == "condition")})
        if bad:
            probs.append(f"mode {m.get('index')}: non-finite {', '.join(bad)}")
    if partial or probs:
        return probs
    dof, modes_ = out["dof"], out["modes"]
    if dof > 0 and not modes_:
        return [f"empty listing for {dof} DOF (n_infinite {out.get('n_infinite')})"]
    # a complex pair counts 2 eigenvalues, a real one 1, a rigid-body mode 1 or 2 (double s = 0);
    # a periodic case lists multipliers: a real one (negative: exponent ln|μ|/T + iπ/T) is 1
    count = sum(1 if "multiplier" in m and m["multiplier"][1] == 0 else
                2 if m["kind"] in ("oscillatory", "flutter") else 1 for m in modes_)
    rigid = sum(1 for m in modes_ if m["kind"] == "rigid-body")
    target = 2 * dof - int(out.get("n_infinite", 0))
    if not count <= target <= count + rigid:
        probs.append(f"listing accounts for {count}..{count + rigid} of {target} finite "
                     f"eigenvalues ({dof} DOF, {out.get('n_infinite')} infinite)")
    order = {"stable": 0, "critical": 1, "unstable": 2}
    # DESIGN §6: the modes that are rigid-body by construction are not counted
    worst = max((m["stability"] for m in modes_ if not m.get("rigid_body")), key=order.get,
                default="critical")
    if out["verdict"] != worst:
        probs.append(f"verdict {out['verdict']} but the worst mode is {worst}")
    return probs


def classify(r) -> tuple[str, str]:
    """(outcome, detail): ok-accepted, ok-refused, ok-failed-check, or a failure kind."""
    argv, code, err = r["argv"], r["code"], r["stderr"]
    if code == "hang":
        where = (r["traceback"] or "").splitlines()[-1:]
        return "hang", f"no answer within {TIMEOUT} s (at {', '.join(where) or '?'})"
    if r["traceback"] is not None:
        return "traceback", r["traceback"].strip().splitlines()[-1]
    if "Traceback" in err:
        return "traceback", err.strip().splitlines()[-1]
    if r["warnings"]:
        return "warning", r["warnings"][0]
    if r["fd_stdout"]:
        return "output", f"C code wrote to stdout: {r['fd_stdout'][:200]!r}"
    if code == 2:
        lines = err.splitlines()
        if len(lines) != 1 or not lines[0].startswith("mbseig: "):
            return "stderr", f"exit 2 with stderr {err!r}"
        return "ok-refused", lines[0]
    if code == 1 and argv[0] == "check":
        return "ok-failed-check", ""
    if code != 0:
        return "exit", f"exit code {code!r}"
    if err:
        return "stderr", f"exit 0 with stderr {err!r}"
    if "--json" in argv:
        try:
            out = _strict_json(r["stdout"])
        except ValueError as exc:
            return "output", f"invalid JSON: {exc}"
        if argv[0] == "modes":
            partial = any(a in argv for a in ("--n-modes", "--band-hz", "--target-hz"))
            probs = _listing_problems(out, partial)
            if probs:
                return "listing", probs[0]
        elif argv[0] == "linearize":
            bad = _finite_numbers({k: out.get(k) for k in ("M", "P", "Q", "N", "A", "q0", "lam0")
                                   if out.get(k) is not None})
            if bad:
                return "output", f"non-finite linearization output at {bad[0]}"
    return "ok-accepted", ""


# outcomes whose root cause lies in another part of the code, worked on under other issues:
# counted and reported (an xfail naming the area), not failed here; tests/test_input_rules.py
# holds the eigen area's minimal reproductions
AREAS = {
    "eigen area, issue 13/17 eigen part": ("mbseig/eigen/", "mbseig/modal/",
                                           "mbseig/casefile/matrices.py", "mbseig.eigen",
                                           "mbseig.modal"),
    "statics area, issue 10": ("mbseig/statics/", "mbseig.statics"),
    "spatial area, issue 11": ("mbseig/casefile/spatial.py", "mbseig/model/spatial",
                               "mbseig.model.spatial"),
}


def area_of(r, kind, detail) -> str:
    """The area a failure's root cause lies in: one of AREAS, or "own"."""
    if kind == "listing" or (kind == "output" and "On entry to " in detail):
        return "eigen area, issue 13/17 eigen part"  # the listing; LAPACK's complaint
    if kind in ("traceback", "hang"):
        frames = [f for f in re.findall(r'File "([^"]+)"', r["traceback"] or "") if "/mbseig/" in f]
        where = frames if kind == "hang" else frames[-1:]  # a hang: the stage it was in
    elif kind == "warning":
        stack = [f for f in r["warning_stacks"][0] if not f.split(":")[0].endswith("numerics.py")]
        where = stack[-1:] + [r["warning_modules"][0], detail.split(":")[0]]
    else:
        return "own"
    for area, marks in AREAS.items():
        if any(m in w for w in where for m in marks) or (
                kind == "warning" and area.startswith("eigen") and any(
                    f"{f}:" in detail for f in ("dense.py", "partial.py", "measures.py",
                                                "matrices.py"))):
            return area
    return "own"


STATS: Counter = Counter()
FAILURES: list = []  # every failure, with MBSEIG_FUZZ_REPORT
OTHER_FAILURES: list = []  # the eigen area's, per test


def check_outcome(r, strategy, files):
    kind, detail = classify(r)
    STATS[f"{strategy}:{kind}"] += 1
    STATS["cases"] += 1
    if kind.startswith("ok-"):
        return
    area = area_of(r, kind, detail)
    STATS[f"{area.split(',')[0]}:{kind}"] += 1
    record = {"strategy": strategy, "kind": kind, "area": area, "detail": detail,
              "argv": r["argv"], "stderr": r["stderr"][-2000:], "traceback": r["traceback"],
              "warnings": r["warnings"][:3], "warning_stack": (r["warning_stacks"] or [[]])[0][-6:],
              "files": {k: (v if isinstance(v, str) else repr(v[:400])) for k, v in files.items()}}
    if REPORT:
        FAILURES.append(record)
        return
    if area != "own":
        OTHER_FAILURES.append(record)
        return
    raise AssertionError(json.dumps(record, indent=1, default=str))


@pytest.fixture(scope="module", autouse=True)
def _report_and_tree_check():
    before = _tree_snapshot()
    yield
    after = _tree_snapshot()
    if REPORT:
        Path(REPORT).write_text(json.dumps({"stats": dict(sorted(STATS.items())),
                                            "failures": FAILURES}, indent=1, default=str))
    assert before == after, f"files changed outside the temporary folder: {before ^ after}"


# every name a fuzzed run reads or writes; found outside its temporary folder = a stray write
RUN_FILES = {"case.toml", "m.npz", "lin.npz", "x.npz", "x.mat", "x.json", "x.txt", "sub",
             *CASE_TEXT}


def _tree_snapshot():
    """The bundled cases with their times, and which of the runs' file names exist in the
    repository, its tests/ folder or the working directory (where a stray write would land)."""
    out = {(p.name, p.stat().st_mtime_ns) for p in CASES.iterdir()}
    for folder in (ROOT, ROOT / "tests", Path.cwd()):
        out |= {(str(folder / n), 0) for n in RUN_FILES if (folder / n).exists()}
    return frozenset(out)


def _settings(strategy):
    n = max(1, int(TOTAL * SHARE[strategy])) if TOTAL else SHORT[strategy]
    return settings(max_examples=n, deadline=None, derandomize=not os.environ.get(
        "MBSEIG_FUZZ_RANDOM"), database=None, print_blob=True,
        suppress_health_check=list(HealthCheck))


# ---------------------------------------------------------------------------------------------
# strategies
# ---------------------------------------------------------------------------------------------
COMMANDS = [["modes", "--json"], ["modes", "--json"], ["modes", "--json"], ["modes"],
            ["linearize", "--json"], ["linearize", "--out", "lin.npz"], ["linearize"]]
CHECKABLE = ["pendulum.toml", "double_pendulum.toml", "four_bar.toml", "chain_damped.toml",
             "rotating_mass.toml", "ziegler_pendulum.toml"]
_VALUE_RE = re.compile(r"(?m)^(\s*[A-Za-z_][\w\-]*\s*=\s*)(.+?)\s*(#.*)?$")


@st.composite
def case_run(draw, mutation):
    """(files, argv): a mutated case as case.toml and a command on it."""
    name, text = draw(mutation)
    cmd = list(draw(st.sampled_from(COMMANDS)))
    if name in CHECKABLE and draw(st.integers(0, 9)) == 0:
        cmd = ["check", "--json", "--modes", "1", "--periods", "2"]
    return {"case.toml": text}, [cmd[0], "case.toml", *cmd[1:]]


@st.composite
def text_mutation(draw):
    name = draw(st.sampled_from(sorted(CASE_TEXT)))
    text = CASE_TEXT[name]
    for _ in range(draw(st.integers(1, 3))):
        op = draw(st.sampled_from(["value", "value", "value", "rename", "dup_line", "del_line",
                                   "dup_table", "truncate", "bytes"]))
        lines = text.splitlines(keepends=True)
        if not lines:
            break
        if op == "value":
            matches = list(_VALUE_RE.finditer(text))
            if not matches:
                continue
            m = draw(st.sampled_from(matches))
            new = toml_value(draw(VALUES))
            text = text[:m.start(2)] + new + text[m.end(2):]
        elif op == "rename":
            matches = list(_VALUE_RE.finditer(text))
            if not matches:
                continue
            m = draw(st.sampled_from(matches))
            key = draw(st.sampled_from(["name", "mass", "lenght", "points", "type", "x", "repeat",
                                        "enabled", "elements", "stiffness", "position"]))
            text = text[:m.start(1)] + key + " = " + text[m.end(1):]
        elif op == "dup_line":
            k = draw(st.integers(0, len(lines) - 1))
            lines.insert(k, lines[k])
            text = "".join(lines)
        elif op == "del_line":
            k = draw(st.integers(0, len(lines) - 1))
            del lines[k]
            text = "".join(lines)
        elif op == "dup_table":
            heads = [k for k, ln in enumerate(lines) if ln.startswith("[")]
            if not heads:
                continue
            k = draw(st.sampled_from(heads))
            end = next((j for j in range(k + 1, len(lines)) if lines[j].startswith("[")),
                       len(lines))
            text = "".join(lines) + "\n" + "".join(lines[k:end])
        elif op == "truncate":
            text = text[:draw(st.integers(0, len(text)))]
        else:
            raw = text.encode()
            k = draw(st.integers(0, len(raw)))
            junk = draw(st.sampled_from([b"\xff\xfe", b"\x00", b"\xc3", b"\x80\x80", b"\r"]))
            return name, raw[:k] + junk + raw[k:]
    return name, text


def _paths(obj, prefix=()):
    """Every (path, value) of a parsed TOML tree."""
    yield prefix, obj
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for k, v in enumerate(obj):
            yield from _paths(v, prefix + (k,))


def _get(obj, path):
    for p in path:
        obj = obj[p]
    return obj


@st.composite
def data_mutation(draw):
    name = draw(st.sampled_from(sorted(CASE_DATA)))
    data = copy.deepcopy(CASE_DATA[name])
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p, _ in _paths(data) if p]
        path = draw(st.sampled_from(paths))
        parent, key = _get(data, path[:-1]), path[-1]
        op = draw(st.sampled_from(["replace", "replace", "replace", "scale", "delete", "add",
                                   "duplicate"]))
        value = parent[key]
        if op == "replace":
            parent[key] = draw(VALUES)
        elif op == "scale":
            factor = draw(st.sampled_from([1e300, 1e-300, 1e150, 1e-150, -1.0, 1e20, 1e-20, 0.0,
                                           1e99, 1e-99, 1e50, 1e-50]))
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                parent[key] = float(value) * factor
            elif isinstance(value, str):
                parent[key] = f"({value})*{factor!r}"
        elif op == "delete":
            del parent[key]
        elif op == "add" and isinstance(value, dict):
            value[draw(st.sampled_from(["name", "extra", "mass", "repeat", "enabled", "x"]))] = \
                draw(VALUES)
        elif op == "duplicate" and isinstance(parent, list):
            parent.insert(key, copy.deepcopy(value))
    return name, dump_toml(data)


PARAM_OPTS = {
    "modes": [["--n-modes", "K"], ["--target-hz", "F"], ["--band-hz", "F", "F"],
              ["--refine-modes", "K"], ["--refine-fmax", "F"], ["--accuracy", "F"],
              ["--solver", "S"], ["--config", "C"], ["--reactions"]],
    "linearize": [["--config", "C"], ["--out", "O"]],
    "check": [["--modes", "M"], ["--amplitude", "F"], ["--periods", "F"], ["--efolds", "F"],
              ["--delta-rtol", "F"], ["--omega-rtol", "F"], ["--ode-rtol", "F"]],
}
ARG_TEXT = ["0", "-1", "1", "2", "3", "1e308", "-1e308", "nan", "inf", "-inf", "1e-320", "abc",
            "", "1.5", "1e9", "5"]


@st.composite
def args_mutation(draw):
    name = draw(st.sampled_from(sorted(CASE_TEXT)))
    cmd = draw(st.sampled_from(["modes", "modes", "linearize"] +
                               (["check"] if name in CHECKABLE else [])))
    argv = [cmd, name, "--json"]
    if cmd == "check":
        argv += ["--periods", "2", "--modes", "1"]
    params = list(CASE_DATA[name].get("parameters", {})) + ["zz"]
    for _ in range(draw(st.integers(0, 3))):
        if params and draw(st.booleans()):
            p = draw(st.sampled_from(params))
            v = draw(st.sampled_from(STRINGS + [repr(x) for x in NUMBERS]))
            argv += ["--param", f"{p}={v}"]
        else:
            opt = draw(st.sampled_from(PARAM_OPTS[cmd]))
            argv.append(opt[0])
            for slot in opt[1:]:
                if slot == "S":
                    argv.append(draw(st.sampled_from(["auto", "eigh", "qz", "companion",
                                                      "proportional", "partial-eigh", "bogus"])))
                elif slot == "C":
                    confs = list(CASE_DATA[name].get("configurations", {})) + ["nope"]
                    argv.append(draw(st.sampled_from(confs)))
                elif slot == "O":
                    argv.append(draw(st.sampled_from(["x.npz", "x.mat", "x.json", "x.txt",
                                                      "sub/x.npz", "."])))
                elif slot == "M":
                    argv.append(draw(st.sampled_from(["1", "0", "1-3", "99", "a", "1,1", "-1"])))
                else:
                    argv.append(draw(st.sampled_from(ARG_TEXT)))
    return {name: CASE_TEXT[name]}, argv


LINEAR_TOML = """schema_version = 1
kind = "linear"
title = "fuzzed linear case"
[parameters]
Omega = 3.0
[matrices]
M = {{ file = "m.npz", key = "{mk}" }}
P = {{ file = "m.npz", key = "P" }}
Q = [{{ factor = "{qf}", matrix = {{ file = "m.npz", key = "Q" }} }}]
"""
_BASE = {"M": np.eye(2), "P": 6.0 * np.array([[0.0, -1.0], [1.0, 0.0]]), "Q": -5.0 * np.eye(2)}


def _mutate_array(draw, A, op):
    if op == "scale":
        return A * draw(st.sampled_from([1e300, -1e300, 1e-300, 1e-320, 5e-324, 1e200, 1e150,
                                         1e-150, 0.0]))
    if op == "complex":
        return A + 1j * draw(st.sampled_from([0.0, 1.0, 1e-300, 1e300]))
    if op == "int":
        return A.astype(np.int64)
    if op == "object":
        return np.array([["a", 1], [None, 2.0]], dtype=object)
    if op == "shape":
        return draw(st.sampled_from([np.ones(2), np.ones((2, 3)), np.ones((3, 3)),
                                     np.ones((2, 2, 2)), np.ones((1, 1)), np.array(1.0)]))
    if op == "entry":
        B = A.copy()
        B[draw(st.integers(0, 1)), draw(st.integers(0, 1))] = draw(st.sampled_from(
            [math.nan, math.inf, 1e308, 5e-324, 1e-320, -1e308]))
        return B
    if op == "empty":
        return np.zeros((0, 0))
    if op == "drop":
        return None
    if op == "dtype":
        return A.astype(draw(st.sampled_from([np.float16, np.float32, np.bool_, np.uint8,
                                              np.complex64])))
    return A


@st.composite
def npz_mutation(draw):
    arrays = {k: v.copy() for k, v in _BASE.items()}
    raw_tail = None
    for key in draw(st.lists(st.sampled_from(["M", "P", "Q"]), min_size=1, max_size=2,
                             unique=True)):
        A = _BASE[key]
        op = draw(st.sampled_from(["scale", "complex", "int", "object", "shape", "entry",
                                   "empty", "drop", "bytes", "dtype"]))
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")  # casts and overflow while making hostile arrays
            arrays[key] = _mutate_array(draw, A, op)
        if arrays[key] is None:
            del arrays[key]
        if op == "bytes":
            raw_tail = draw(st.sampled_from(["truncate", "empty", "junk"]))
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    blob = buf.getvalue()
    if raw_tail == "truncate":
        blob = blob[:draw(st.integers(0, len(blob) - 1))]
    elif raw_tail == "empty":
        blob = b""
    elif raw_tail == "junk":
        blob = b"PK\x03\x04" + bytes(draw(st.lists(st.integers(0, 255), max_size=64)))
    mk = draw(st.sampled_from(["M", "M", "M", "missing"]))
    qf = draw(st.sampled_from(["1", "1", "1e300", "1e-300", "-1", "0", "1e308"]))
    text = LINEAR_TOML.format(mk=mk, qf=qf)
    cmd = draw(st.sampled_from([["modes", "--json"], ["linearize", "--json"], ["modes"]]))
    return {"case.toml": text, "m.npz": blob}, [cmd[0], "case.toml", *cmd[1:]]


# ---------------------------------------------------------------------------------------------
# the tests
# ---------------------------------------------------------------------------------------------
def fuzz(strategy, cases, tmp_path):
    """Run ``strategy``'s examples; failures in this part of the code fail the test at once
    (Hypothesis shrinks them), those of the eigen area are reported as an xfail with the
    first of them (tests/test_input_rules.py holds their minimal reproductions)."""

    @_settings(strategy)
    @given(case=cases)
    def run(case):
        files, argv = case
        check_outcome(run_cli(argv, files, tmp_path), strategy, files)

    OTHER_FAILURES.clear()
    run()
    if OTHER_FAILURES and not REPORT:
        first = OTHER_FAILURES[0]
        areas = sorted({f["area"] for f in OTHER_FAILURES})
        pytest.xfail(f"{'; '.join(areas)}: {len(OTHER_FAILURES)} example(s), first "
                     f"{first['kind']}: {first['detail'][:300]} ({first['argv']})")


def test_fuzz_case_text(tmp_path):
    fuzz("text", case_run(text_mutation()), tmp_path)


def test_fuzz_case_data(tmp_path):
    fuzz("data", case_run(data_mutation()), tmp_path)


def test_fuzz_command_line(tmp_path):
    fuzz("args", args_mutation(), tmp_path)


def test_fuzz_npz_matrices(tmp_path):
    fuzz("npz", npz_mutation(), tmp_path)
