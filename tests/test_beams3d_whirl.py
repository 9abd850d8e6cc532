"""Whirl "none" from the lateral fraction (mbseig.model.spatial_whirl, NONE_FRACTION = 0.1):
the shared overhung rotor under gravity, whose static sag couples torsion and axial modes to
lateral motion at 3e-4 to 8e-3 of their motion."""

from pathlib import Path

import numpy as np
import pytest

from mbseig.casefile import read_case
from mbseig.linear import linearize
from mbseig.modal import modes
from mbseig.model.spatial_whirl import NONE_FRACTION, lateral_fraction, whirl
from mbseig.statics import equilibrium, solved
from mbseig.studies.campbell import campbell

# the format examples of DESIGN §8 (../shared/examples beside the checkout)
EXAMPLE = Path(__file__).resolve().parents[2] / "shared" / "examples" / "overhung_rotor.toml"
pytestmark = pytest.mark.skipif(not EXAMPLE.exists(), reason="shared example not present")


def _modes(**params):
    model = read_case(EXAMPLE).build(**params)
    eq = equilibrium(model)
    model = solved(model, eq)
    return model, eq, modes(linearize(model, eq))


def test_sag_coupled_torsion_is_not_whirl():
    model, eq, md = _modes()
    lam = md.eigenvalues
    labels = [whirl(model, eq.q, md.shapes[:, k], lam[k]) for k in range(len(md))]
    frac = np.array([lateral_fraction(model, eq.q, md.shapes[:, k]) for k in range(len(md))])
    # The torsion mode (about 289 rad/s: the 1e4 N m/rad lock against the disk's 0.09 kg m²
    # plus the shaft, sqrt(k/J) = 333 rad/s for the disk alone) has no lateral whirl.
    k_t = int(np.argmin(abs(lam.imag - 289.4)))
    assert abs(lam[k_t].imag - 289.4) < 1.0
    assert frac[k_t] < 1e-3 and labels[k_t] == "none"
    # Every mode is either bending (fraction near 1, labelled by its orbit) or coupled by the
    # sag (well below the threshold, "none"): nothing lies near the threshold.
    assert np.all((frac > 0.99) | (frac < NONE_FRACTION / 10))
    for f, w in zip(frac, labels, strict=True):
        assert (w == "none") == (f < NONE_FRACTION)
    # The two lowest (the disk's conical pair) keep their labels: backward below forward.
    assert labels[:2] == ["backward", "forward"]


def test_no_spurious_critical_speed_at_the_torsion_mode():
    res = campbell(EXAMPLE, "Omega", [260.0, 320.0])
    near = [c for c in res.critical_speeds if 260.0 <= c["value"] <= 320.0]
    assert near == []  # the torsion mode at 289 rad/s crosses 1x here, with whirl "none"
