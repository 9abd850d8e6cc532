"""Stability reports rendered from computed data: :func:`~mbseig.report.build.render_report`
formats what :func:`mbseig.studies.report_data.report_data` computed, as Markdown and
self-contained HTML (:mod:`~mbseig.report.render`).  Figures come from :mod:`mbseig.plots`.
This package computes nothing (``mbseig.write_report`` = render(report_data(case)))."""

from .build import build_report, render_report
from .render import render_html, render_markdown

__all__ = ["build_report", "render_report", "render_html", "render_markdown"]
