"""Stability reports: blocks built from the studies (:mod:`~mbseig.report.build`) and rendered
as Markdown and self-contained HTML (:mod:`~mbseig.report.render`).  Figures come from
:mod:`mbseig.plots`."""

from .build import build_report, write_report
from .render import render_html, render_markdown

__all__ = ["build_report", "write_report", "render_html", "render_markdown"]
