"""PDF output of a :class:`~analysis.report.Report`: the HTML report typeset by WeasyPrint.

The PDF comes from the same HTML source as the browser view, through its print CSS (A4, page
numbers "page n of N", headings kept with their figures, wide tables on landscape pages,
vector figures). WeasyPrint is a core dependency; an environment without it gets a
:class:`~predict.errors.MissingDependencyError` naming the package — there is no second layout
with different content.
"""

from __future__ import annotations

import logging

from crankbench.predict._validate import require

__all__ = ["write_pdf"]

log = logging.getLogger("crankbench")


def write_pdf(report, path) -> str:
    """Write ``report`` as PDF to ``path`` (no overwrite check: the caller's job).

    Parameters
    ----------
    report : Report
    path : path-like

    Returns
    -------
    str
        The engine used ('weasyprint').

    Raises
    ------
    MissingDependencyError
        WeasyPrint is not installed (``pip install weasyprint``).
    """
    weasyprint = require("weasyprint", extra="pdf", feature="PDF reports")
    # WeasyPrint logs every unsupported CSS property of the SVGs at WARNING: keep them quiet
    wlog = logging.getLogger("weasyprint")
    level = wlog.level
    wlog.setLevel(logging.ERROR)
    try:
        weasyprint.HTML(string=report.to_html()).write_pdf(str(path))
    finally:
        wlog.setLevel(level)
    return "weasyprint"
