"""PDF output of a :class:`~analysis.report.Report`.

With the optional ``weasyprint`` package (``pip install 'crankbench[pdf]'``) the HTML report
is typeset as it looks in a browser. Without it, a matplotlib fallback lays out the same
content on A4 pages: headings, key/value lists and tables as monospaced text, figures from
their embedded PNG. ``engine='auto'`` picks weasyprint when it imports.
"""

from __future__ import annotations

import io
import logging
import textwrap
from pathlib import Path

from crankbench.predict._validate import check_option, require
from crankbench.predict.errors import ConfigError

__all__ = ["write_pdf", "ENGINES"]

log = logging.getLogger("crankbench")

ENGINES = ("auto", "weasyprint", "matplotlib")

_A4 = (8.27, 11.69)  # inches
_LINES_PER_PAGE = 78
_WRAP = 118


def write_pdf(report, path, *, engine: str = "auto") -> str:
    """Write ``report`` as PDF to ``path`` (no overwrite check: the caller's job).

    Parameters
    ----------
    report : Report
    path : path-like
    engine : {'auto', 'weasyprint', 'matplotlib'}

    Returns
    -------
    str
        The engine used.
    """
    check_option(engine, "engine", ENGINES, error=ConfigError)
    if engine in ("auto", "weasyprint"):
        try:
            weasyprint = require("weasyprint", extra="pdf", feature="PDF typesetting")
        except ImportError:
            if engine == "weasyprint":
                raise
            log.info("weasyprint not installed: PDF laid out with matplotlib instead")
        else:
            weasyprint.HTML(string=report.to_html()).write_pdf(str(path))
            return "weasyprint"
    _matplotlib_pdf(report, Path(path))
    return "matplotlib"


def _lines_for(report):
    """Flatten the report into (style, text) lines and ('figure', png bytes) entries."""
    out = [("title", report.title)]
    if report.subtitle:
        out.append(("muted", report.subtitle))
    out.append(("muted", f"Created {report.created.isoformat()} UTC"))
    if report._summary:
        out.append(("h2", "Verdict"))
        for label, passed, detail in report._summary:
            mark = "INFO" if passed is None else ("PASS" if passed else "FAIL")
            for k, chunk in enumerate(textwrap.wrap(f"{mark}  {label}"
                                                    + (f" — {detail}" if detail else ""),
                                                    _WRAP)):
                out.append(("fail" if passed is False and k == 0 else "text", chunk))
    for sec, items in report._iter_items():
        out.append(("h2", sec.title))
        for item in items:
            if item.title and item.title != sec.title:
                out.append(("h3", item.title))
            if item.kind == "kv":
                width = max((len(k) for k, _ in item.payload["rows"]), default=0)
                for k, v in item.payload["rows"]:
                    for j, chunk in enumerate(textwrap.wrap(str(v), _WRAP - width - 2) or [""]):
                        out.append(("mono", f"{k if j == 0 else '':<{width}}  {chunk}"))
            elif item.kind in ("table", "checks"):
                if item.kind == "checks":
                    cols = ["check", "value", "limit", "units", "result", "detail"]
                    rows = [[r["check"], r["value"], r["limit"], r["units"],
                             "PASS" if r["passed"] else "FAIL", r["detail"]]
                            for r in item.payload["rows"]]
                else:
                    cols, rows = item.payload["columns"], item.payload["rows"]
                out.extend(("mono", line) for line in _text_table(cols, rows))
                if item.caption:
                    out.extend(("muted", c) for c in textwrap.wrap(item.caption, _WRAP))
            elif item.kind == "text":
                for p in item.payload["paragraphs"]:
                    out.extend(("text", c) for c in textwrap.wrap(p, _WRAP))
            elif item.kind == "figure":
                out.append(("figure", item.payload["png"]))
                if item.caption:
                    out.extend(("muted", c) for c in textwrap.wrap(item.caption, _WRAP))
            elif item.kind == "html":
                out.append(("muted", "(HTML content shown in the HTML report only)"))
    return out


def _text_table(cols, rows, max_width=24):
    def cut(v):
        v = str(v)
        return v if len(v) <= max_width else v[:max_width - 1] + "…"

    cells = [[cut(c) for c in cols]] + [[cut(v) for v in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(cols))]
    lines = ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    # very wide tables: wrap each row onto continuation lines
    return [chunk for line in lines for chunk in (textwrap.wrap(line, 150,
                                                                drop_whitespace=False) or [""])]


_STYLE = {"title": dict(size=16, weight="bold", lines=2.2),
          "h2": dict(size=12.5, weight="bold", lines=1.9),
          "h3": dict(size=10, weight="bold", lines=1.4),
          "text": dict(size=8, lines=1.0),
          "fail": dict(size=8, lines=1.0, color="#b3261e", weight="bold"),
          "muted": dict(size=7.5, lines=1.0, color="#5b6670"),
          "mono": dict(size=6.2, lines=0.85, family="monospace")}


def _matplotlib_pdf(report, path: Path) -> None:
    import matplotlib

    matplotlib.use(matplotlib.get_backend())  # keep whatever backend is set (Agg in CLI)
    import matplotlib.image as mpimg
    import matplotlib.pyplot as plt
    from matplotlib.backends.backend_pdf import PdfPages

    entries = _lines_for(report)
    top, bottom, left = 0.95, 0.05, 0.07
    line_h = (top - bottom) / _LINES_PER_PAGE
    with PdfPages(path) as pdf:
        fig = plt.figure(figsize=_A4)
        y = top
        pages = 0

        def new_page():
            nonlocal fig, y, pages
            fig.text(0.5, 0.02, f"{report.title} — page {pages + 1}", ha="center", fontsize=6,
                     color="#5b6670")
            pdf.savefig(fig)
            plt.close(fig)
            pages += 1
            fig = plt.figure(figsize=_A4)
            y = top

        def fig_size(content):
            img = mpimg.imread(io.BytesIO(content), format="png")
            h_px, w_px = img.shape[:2]
            width = 0.86
            height = min(width * h_px / w_px * _A4[0] / _A4[1], 0.55)
            return img, height * w_px / h_px * _A4[1] / _A4[0], height

        for k, (style, content) in enumerate(entries):
            nxt = entries[k + 1] if k + 1 < len(entries) else (None, None)
            if style in ("h2", "h3") and nxt[0] == "figure":
                # keep a heading with its figure
                _, _, h_next = fig_size(nxt[1])
                if y - line_h * _STYLE[style]["lines"] - h_next < bottom:
                    new_page()
            if style == "figure":
                img, width, height = fig_size(content)
                if y - height < bottom:
                    new_page()
                ax = fig.add_axes([left, y - height, width, height])
                ax.imshow(img)
                ax.axis("off")
                y -= height + line_h
                continue
            st = _STYLE[style]
            step = line_h * st["lines"]
            if y - step < bottom:
                new_page()
            if style in ("h2",) and y < bottom + 8 * line_h:
                new_page()  # no heading stranded at the page foot
            fig.text(left, y - step * 0.8, content, fontsize=st["size"],
                     fontweight=st.get("weight", "normal"), color=st.get("color", "#1d2329"),
                     family=st.get("family", "sans-serif"), va="baseline")
            y -= step
        fig.text(0.5, 0.02, f"{report.title} — page {pages + 1}", ha="center", fontsize=6,
                 color="#5b6670")
        pdf.savefig(fig)
        plt.close(fig)
