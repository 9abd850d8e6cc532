"""Figures: sweeps, pole maps, mechanism mode shapes, time-domain checks, the report's summary
figures, and animated mode shapes (:mod:`mbseig.plots.animation`, GIF) (the drawing layer).

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot, so no global
state changes: the backend a notebook or application chose stays as it is, and no figure is kept
alive by a figure manager.  :func:`save` writes one as a PNG without metadata, so the output is
byte-identical for identical inputs.  matplotlib is imported here only, when a figure is asked
for.  The functions take result objects by their attributes (duck typing) and import no stage.
"""

from .common import decade_scale, save
from .mechanism import mechanism_layout, mechanism_modes, project_constraints
from .poles import plot_check, pole_map, speed_accuracy
from .summary import summary_poles, tornado
from .sweeps import (
           bifurcation_diagram,
           modes_vs_parameter,
           root_locus,
           stability_chart,
           stability_map,
)

__all__ = ["root_locus", "modes_vs_parameter", "stability_map", "bifurcation_diagram",
           "stability_chart", "pole_map", "mechanism_modes", "plot_check", "speed_accuracy", "save",
           "decade_scale", "mechanism_layout", "project_constraints", "summary_poles", "tornado"]
