"""The case files of the spatial peer models, written for mbseig as a user would (the same
bodies, joints and dashpots EXUDYN is given)."""

from __future__ import annotations


def pendulum_case(p):
    return f"""
schema_version = 1
dimension = 3
source = "bench: spherical pendulum with rotational dashpots at the pivot (non-proportional)"
gravity = [0.0, 0.0, {-p['g']!r}]
[[points]]
name = "O"
position = [0.0, 0.0, 0.0]
fixed = true
[[bodies]]
name = "bob"
mass = {p['m']!r}
com = [0.0, 0.0, {-p['l']!r}]
inertia = [{p['Jx']!r}, {p['Jy']!r}, {p['Jz']!r}]
[[joints]]
name = "pivot"
type = "spherical"
bodies = ["ground", "bob"]
at = [0.0, 0.0, 0.0]
[[forces]]
name = "pivot dashpots"
type = "bushing"
bodies = ["ground", "bob"]
at = [0.0, 0.0, 0.0]
stiffness = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
damping = [0.0, 0.0, 0.0, {p['cx']!r}, {p['cy']!r}, {p['cz']!r}]
"""


def double_case(p):
    return f"""
schema_version = 1
dimension = 3
source = "bench: spatial double pendulum (cases/spatial_double_pendulum.toml)"
gravity = [0.0, 0.0, {-p['g']!r}]
[[points]]
name = "O"
position = [0.0, 0.0, 0.0]
fixed = true
[[points]]
name = "A"
position = [0.0, 0.0, {-p['l1']!r}]
[[bodies]]
name = "upper"
mass = {p['m1']!r}
com = [0.0, 0.0, {-p['c1']!r}]
inertia = [{p['J1']!r}, {p['J1']!r}, {p['Ja']!r}]
points = ["O", "A"]
[[bodies]]
name = "lower"
mass = {p['m2']!r}
com = [0.0, 0.0, {-(p['l1'] + p['c2'])!r}]
inertia = [{p['J2']!r}, {p['J2']!r}, {p['Ja']!r}]
points = ["A"]
"""
