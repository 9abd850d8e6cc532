"""The model of a rotor case along its speed: one full build, the speeds re-read at each value.

Over a Campbell sweep only the gyroscopic terms change when the swept parameter enters nothing
but the spin of spinning beams (``[[beams]].spin``) and the speed of rotor forces
(``type = "rotor"``, ``speed``).  :class:`SpeedUpdate` builds the case once and, at each value,
re-reads those fields with the reader's own evaluation (:meth:`Fields.num`) and gives the
elements of the one build with their speeds replaced: equal, element by element, to a full
build at that value.  Both forces are proportional to the velocities (a beam's −Ω TᵀGT q̇, a
rotor's −J_p Ω ȧ), so they vanish at rest: the equilibrium of every value is the first one's,
and its stiffness, mass and constraints are too (what :mod:`mbseig.studies.campbell` reuses).
``reason`` says where else the parameter (or a parameter computed from it) enters; a full
build is then needed at every value.
"""

from __future__ import annotations

import copy
import dataclasses

from ..model.beam3d import Beam3DElement
from ..model.beam3d_lagrange import LagrangeBeam3DElement
from ..model.spatial_forces import Rotor
from .element_readers import ScalarUpdate
from .fields import Fields

__all__ = ["SpeedUpdate"]


class SpeedUpdate(ScalarUpdate):
    """The model at each value of a speed parameter (module docstring)."""

    def __init__(self, data, config, overrides, axis, model0):
        self._parameters(data, config, overrides, axis, model0)
        self.spins, self.rotors = [], []  # (label, item) of the fields re-read
        if isinstance(axis, tuple) or data.get("dimension") != 3 or not self._known():
            self.reason = "not one parameter of a 3-D case"
            return
        rest = dict(data)
        for section, key, kind, out in (("beams", "spin", None, self.spins),
                                        ("forces", "speed", "rotor", self.rotors)):
            items = data.get(section) or []
            if not isinstance(items, list) or any(not isinstance(x, dict) or "repeat" in x
                                                  for x in items):
                self.reason = f"[[{section}]] has repeated or unreadable items"
                return
            kept = []
            for k, item in enumerate(items):
                value = item.get(key)
                if (kind is None or item.get("type") == kind) and isinstance(value, str) \
                        and self._uses(value):
                    name = item.get("name")
                    out.append((f"{section}[{k}]" + (f" {name!r}" if isinstance(name, str)
                                                      else ""), item))
                    item = {a: b for a, b in item.items() if a != key}
                kept.append(item)
            rest[section] = kept
        if not self.spins and not self.rotors:
            self.reason = f"{self.label} sets no beam's spin and no rotor's speed"
            return
        where = self._anywhere(rest, "")
        if where is not None:
            self.reason = f"{self.label} enters {where}"
        elif self.parameters(self._at(model0.parameters), every=True) != model0.parameters:
            self.reason = "the parameters evaluate differently"  # a safeguard: never seen

    def make(self, p):
        """The model at axis = p, or None where a full build is needed."""
        if self.reason is not None:
            return None
        params = self.parameters(p)
        spin = {label: Fields(item, label, params).num("spin", 0.0)
                for label, item in self.spins}
        speed = {label: Fields(item, label, params).num("speed")
                 for label, item in self.rotors}
        forces = []
        for f in self.model0.forces:
            if isinstance(f, Rotor) and f.name in speed:
                f = dataclasses.replace(f, speed=speed[f.name])
            elif isinstance(f, (Beam3DElement, LagrangeBeam3DElement)):
                beam = f.name.rsplit(" element ", 1)[0]
                if beam in spin:  # (its frames, matrices and planes do not depend on the spin)
                    f = copy.copy(f)
                    object.__setattr__(f, "spin", spin[beam])
            forces.append(f)
        flexible = dict(self.model0.flexible or {})
        shafts = []
        for s in flexible.get("shafts", ()):
            if s.name in spin:  # its station map kept (the stations do not move)
                s = copy.copy(s)
                object.__setattr__(s, "speed", float(spin[s.name]))
            shafts.append(s)
        if shafts:
            flexible["shafts"] = type(self.model0.flexible["shafts"])(shafts)
        bodies = dict(flexible.get("bodies") or {})
        for name, rec in bodies.items():
            label = next((lb for lb in spin if lb.endswith(f" {name!r}")), None)
            if label is not None and isinstance(rec, dict) and "spin" in rec:
                bodies[name] = {**rec, "spin": spin[label]}  # the record the reports print
        if bodies:
            flexible["bodies"] = bodies
        model = dataclasses.replace(self.model0, forces=tuple(forces), parameters=params,
                                    flexible=flexible)
        if "_layout" in self.model0.__dict__:  # the same elements' coordinates and rows: the
            model.__dict__["_layout"] = self.model0._layout  # assembly plans are the same
        return model
