"""What the report of a steady motion shows (DESIGN §8; formatted by
:mod:`mbseig.report.steady`): the steady motion analysed
(:func:`mbseig.studies.steady_modes.analyze_steady`), its modes as a
:class:`~mbseig.studies.report_studies.ModeListing`, the least-damped counted mode, the shapes of
the lowest counted modes in the full coordinates, q − q₀(t) = N x of each mode
(:func:`mbseig.studies.steady_modes.mode_shape`), and the time-domain check
(:func:`mbseig.studies.steady_check.check_steady`).  The modes that are rigid-body by
construction (the motion's cyclic directions: position, heading, speed) are named in the table
and not drawn.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .report_studies import least_damped, least_mode_record, listing_of_rows

__all__ = ["SteadyReport", "steady_report_data", "STEADY_RULE"]

#: the rule of a steady mode's tolerance (:mod:`mbseig.studies.steady_modes`)
STEADY_RULE = "10 κ max(η, n ε) max(|s|, 1)"


@dataclass(frozen=True)
class SteadyReport:
    """Everything the report of a steady motion prints (module docstring)."""

    name: str
    description: str
    config: str | None
    analysis: object = field(repr=False)
    listing: object = field(repr=False)
    least: int | None = None
    least_mode: dict | None = None
    drawn: tuple = ()  # indices of the modes drawn, with their shapes (columns of ``shapes``)
    shapes: np.ndarray = field(default=None, repr=False)
    check: object = None


def steady_report_data(spec, *, config=None, run_check=True, max_drawn=6) -> SteadyReport:
    """Analyse the steady motion of ``spec`` for its report (module docstring); the lowest
    ``max_drawn`` counted modes are drawn."""
    from .steady_check import check_steady
    from .steady_modes import analyze_steady, mode_shape

    a = analyze_steady(spec, config=config)
    listing = listing_of_rows(a.modes, a.verdict, STEADY_RULE)
    least = least_damped(listing)
    drawn = tuple(k for k in range(len(listing)) if listing.rigid_body[k] is None)[:max_drawn]
    n = a.model.n
    shapes = np.zeros((n, len(drawn)), complex)
    for j, k in enumerate(drawn):
        s = complex(listing.eigenvalues[k])
        v = mode_shape(a.linear, s)
        shapes[:, j] = v / max(float(np.max(np.abs(v))), 1e-300)
    chk = check_steady(spec, config=config, periods=5.0) if run_check else None
    return SteadyReport(spec.name, getattr(a.model, "description", "") or
                        str(spec.data.get("title", "")), config, a, listing, least,
                        least_mode_record(listing, least), drawn, shapes, chk)
