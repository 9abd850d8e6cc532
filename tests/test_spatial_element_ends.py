"""The spatial reader records the ends of springs and bushings that act at inline point
references ``{body = ..., at = [...]}`` (model.element_ends, mbseig.model.assembly), so that
drawings show them as springs: each end is a named point of model.points at the position the
case gives (the reference configuration), in the order of the element's difference map."""

import numpy as np
from conftest import write_case

import mbseig

CASE = """
schema_version = 1
title = "pendulum held by an inline spring and a bushing"
dimension = 3
gravity = [0.0, 0.0, -9.81]

[[points]]
name = "P"
position = [0.0, 1.0, -1.0]
fixed = true

[[bodies]]
name = "bob"
mass = 1.0
com = [0.0, 0.0, -1.0]
inertia = [0.1, 0.1, 0.1]

[[joints]]
name = "pivot"
type = "spherical"
bodies = ["ground", "bob"]
at = [0.0, 0.0, 0.0]

[[forces]]
name = "side spring"
type = "spring"
points = [{ body = "ground", at = [1.0, 0.0, -1.0] }, { body = "bob", at = [0.0, 0.0, -1.0] }]
stiffness = 10.0

[[forces]]
name = "mixed spring"
type = "spring"
points = ["P", { body = "bob", at = [0.0, 0.1, -1.0] }]
stiffness = 5.0

[[forces]]
name = "holder"
type = "bushing"
bodies = ["ground", "bob"]
at = [0.0, 0.0, -0.5]
stiffness = [1.0, 1.0, 1.0, 0.0, 0.0, 0.0]
"""


def test_inline_point_ends_recorded(tmp_path):
    model = mbseig.load_case(write_case(tmp_path, CASE))
    ends = model.element_ends
    expected = {"side spring": ([1.0, 0.0, -1.0], [0.0, 0.0, -1.0]),
                "mixed spring": ([0.0, 1.0, -1.0], [0.0, 0.1, -1.0]),
                "holder": ([0.0, 0.0, -0.5], [0.0, 0.0, -0.5])}
    for name, (a, b) in expected.items():
        (key,) = [k for k in ends if k.endswith(f"'{name}'")]
        pa, pb = ends[key]
        assert pa in model.points and pb in model.points
        # positions as the case file gives them (exact: affine maps at the reference)
        np.testing.assert_allclose(model.points[pa](model.q_init), a, atol=1e-15)
        np.testing.assert_allclose(model.points[pb](model.q_init), b, atol=1e-15)
    side = ends[next(k for k in ends if k.endswith("'side spring'"))]
    assert side[1] in model.bodies["bob"]["markers"]  # the body's own station marker
    assert ends[next(k for k in ends if k.endswith("'mixed spring'"))][0] == "P"


def test_inline_ends_move_with_the_body(tmp_path):
    """The body end of a spring is a point of the body: turned with it (a rotation of the bob
    about the pivot moves the end by the same rotation)."""
    model = mbseig.load_case(write_case(tmp_path, CASE))
    key = next(k for k in model.element_ends if k.endswith("'mixed spring'"))
    end = model.points[model.element_ends[key][1]]
    q = model.q_init.copy()
    names = list(model.coordinate_names)
    # rotate the bob by 90° about x: u stays, v → z, w → −y; its CoM (origin) to (0, 1, 0),
    # so the end (0, 0.1, 0) from the CoM goes to (0, 1, 0) + 0.1 z
    for axis, value in zip("xyz", (0.0, 1.0, 0.0), strict=True):
        q[names.index(f"bob.{axis}")] = value
    for vec, value in (("v", (0.0, 0.0, 1.0)), ("w", (0.0, -1.0, 0.0))):
        for axis, x in zip("xyz", value, strict=True):
            q[names.index(f"bob.{vec}.{axis}")] = x
    np.testing.assert_allclose(end(q), [0.0, 1.0, 0.1], atol=1e-15)


def test_spatial_drawing_shows_springs_and_bushings(tmp_path):
    """The 3-D drawing takes its springs from element_ends: a coil between two distinct ends
    (its first and last vertices are the ends, at the reference), a bushing symbol where the
    two ends meet."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from mbseig.plots.spatial import draw_spatial, spatial_layout

    model = mbseig.load_case(write_case(tmp_path, CASE))
    layout = spatial_layout(model)
    assert len(layout["springs"]) == 3
    ax = Figure().add_subplot(projection="3d")
    before = len(ax.lines)
    draw_spatial(ax, model, layout, model.q_init, lambda P: (P[:, 0], P[:, 1], P[:, 2]),
                 colour="k", lw=1.0, symbols=True)
    lines = ax.lines[before:]
    coils = [ln for ln in lines if len(ln.get_data_3d()[0]) == 13]  # 2·6 turns + 1 vertices
    assert len(coils) == 2
    ends = sorted(tuple(np.round(np.array(ln.get_data_3d())[:, k], 12)) for ln in coils
                  for k in (0, -1))
    assert ends == sorted([(1.0, 0.0, -1.0), (0.0, 0.0, -1.0), (0.0, 1.0, -1.0), (0.0, 0.1, -1.0)])
    assert any(ln.get_marker() == "x" for ln in lines)  # the bushing, ends coincident
