"""The display map of a beam model, built for all its triads at once, and the dominant rows
of the modes ranked a block of modes at a time (mbseig.model.naming)."""

import importlib
from pathlib import Path

import numpy as np

import mbseig
from mbseig.model.frames import CoordinateFrames
from mbseig.model.naming import display_map, dominant

CASES = Path(__file__).resolve().parents[1] / "cases"


def test_every_node_rotation_of_an_oblique_beam_reads_as_its_angles():
    """δe = δθ × e on the unit vectors of every node triad of the oblique cantilever (triads
    not along the axes) reads δθ on that node's θx, θy, θz rows: ½ Σ e × (δθ × e) = δθ for
    an orthonormal triad (closed form).  The triads are orthonormal to rounding, so each row
    is exact to a few ε of |δθ|; 1e-14 relative is that with a margin.  A node's translation
    reads as itself exactly (a row of one unit entry)."""
    model = mbseig.load_case(CASES / "cantilever_3d_oblique.toml")
    q = np.asarray(model.q_init, float)
    fr = CoordinateFrames(model)
    dmap = display_map(model, q)
    rows = {name: k for k, name in enumerate(dmap.names)}
    rng = np.random.default_rng(5)
    dq = np.zeros(model.n)
    expected = {}
    for key, members in fr.frames.items():
        vecs = {h.rpartition(".")[2]: fr.vectors[h] for kind, h in members if kind == "v"}
        if set(vecs) != {"u", "v", "w"}:
            continue
        theta, shift = rng.standard_normal(3) * 1e-3, rng.standard_normal(3) * 1e-2
        for e in "uvw":
            idx = [vecs[e][a] for a in "xyz"]
            dq[idx] = np.cross(theta, q[idx])
        pts = [h for kind, h in members if kind == "p"]
        label = dmap.names[rows_of_key(dmap, key)[0]].rsplit(" ", 1)[0]
        if pts:
            dq[[fr.points[pts[0]][a] for a in "xyz"]] = shift
            expected.update({f"{label} {a}": s for a, s in zip("xyz", shift, strict=True)})
        expected.update({f"{label} θ{a}": t for a, t in zip("xyz", theta, strict=True)})
    assert sum(1 for n in expected if " θ" in n) >= 3 * 20  # every node of the beam
    got = dmap.apply(dq)
    for name, value in expected.items():
        if " θ" in name:
            assert abs(got[rows[name]] - value) <= 1e-14 * 1e-3 * 3, name
        else:
            assert got[rows[name]] == value, name


def rows_of_key(dmap, key):
    """The display rows of frame ``key`` (its parts, before they are named)."""
    return [k for k, part in enumerate(dmap.names._parts) if isinstance(part, tuple)
            and part[0] == key]


def test_dominant_rows_do_not_depend_on_the_block_of_modes(monkeypatch):
    """The dominant rows of every mode are the same ranked one mode at a time as all at once
    (the same per-column arithmetic, bitwise)."""
    a = mbseig.analyze(CASES / "cantilever_3d_oblique.toml")
    dmap = a.linear.display
    dmap = dmap() if callable(dmap) else dmap
    at_once = dominant(dmap, a.modes.shapes)
    monkeypatch.setattr(importlib.import_module("mbseig.model.naming"), "DOMINANT_BLOCK", 1)
    assert dominant(dmap, a.modes.shapes) == at_once
    assert len(at_once) == len(a.modes) and all(at_once)
