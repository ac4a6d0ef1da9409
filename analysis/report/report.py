"""The test report: built by ``Report.add_*`` calls, saved as self-contained HTML or PDF.

Every figure is rendered when it is added (PNG as base64, or inline SVG), so the saved HTML
needs no network and no side files, and the figure can be closed at once. Tables are pandas
DataFrames rendered with escaping; limit checks get pass/fail marks. ``save(path)`` writes
atomically and refuses to replace an existing file unless ``overwrite=True``.
"""

from __future__ import annotations

import base64
import datetime as _dt
import hashlib
import html
import io
import logging
import platform
from dataclasses import dataclass, field
from pathlib import Path

from crankbench.predict._validate import check_int, check_option
from crankbench.predict.errors import ConfigError

__all__ = ["Report", "file_sha256", "crankbench_version"]

log = logging.getLogger("crankbench")


def file_sha256(path) -> str:
    """SHA-256 of a file's bytes (hex), read in 1 MiB blocks.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "x.bin"
    >>> _ = p.write_bytes(b"abc")
    >>> file_sha256(p)[:16]
    'ba7816bf8f01cfea'
    """
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def crankbench_version() -> str:
    """Installed crankbench version, or 'unknown (not installed)'."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("crankbench")
    except PackageNotFoundError:
        return "unknown (not installed)"


@dataclass
class _Item:
    kind: str  # 'figure' | 'table' | 'text' | 'kv' | 'checks' | 'html'
    title: str
    caption: str = ""
    payload: dict = field(default_factory=dict)


@dataclass
class _Section:
    title: str
    anchor: str
    items: list = field(default_factory=list)


def _fmt(value, float_format="{:.4g}") -> str:
    import numpy as np

    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (float, np.floating)):
        return "—" if not np.isfinite(value) else float_format.format(float(value))
    if isinstance(value, (list, tuple)):
        return ", ".join(_fmt(v, float_format) for v in value)
    if value is None:
        return "—"
    return str(value)


class Report:
    """A test report assembled section by section.

    Parameters
    ----------
    title : str
    subtitle : str
        e.g. engine and test ids.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> import pandas as pd
    >>> rep = Report("Run-up 6L32")
    >>> rep.add_metadata({"engine": "6L32", "test": "T-001"})
    >>> fig, ax = plt.subplots()
    >>> _ = ax.plot([0, 1], [0, 1])
    >>> rep.add_figure(fig, title="A line", section="Figures")
    >>> rep.add_table(pd.DataFrame({"order": [6.0], "speed_rpm": [400.0]}), title="Criticals")
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "r.html"
    >>> _ = rep.save(out)
    >>> print(rep.n_figures, out.read_text().count("<img"))
    1 1
    """

    def __init__(self, title: str = "crankbench test report", *, subtitle: str = ""):
        self.title = str(title)
        self.subtitle = str(subtitle)
        self.created = _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0)
        self._sections: list[_Section] = []
        self._summary: list[tuple[str, bool | None, str]] = []

    # -- structure --------------------------------------------------------------------------
    def _section(self, title: str | None) -> _Section:
        title = title or "General"
        for s in self._sections:
            if s.title == title:
                return s
        anchor = f"s{len(self._sections) + 1}"
        sec = _Section(title, anchor)
        self._sections.append(sec)
        return sec

    @property
    def sections(self) -> list[str]:
        """Section titles in order."""
        return [s.title for s in self._sections]

    @property
    def n_figures(self) -> int:
        """Number of figures added."""
        return sum(1 for s in self._sections for i in s.items if i.kind == "figure")

    # -- adders -----------------------------------------------------------------------------
    def add_summary(self, label: str, passed: bool | None, detail: str = "") -> None:
        """One line of the verdict box at the top (passed None = informational)."""
        self._summary.append((str(label), None if passed is None else bool(passed), str(detail)))

    def add_metadata(self, items: dict, *, title: str = "Test metadata",
                     section: str | None = None) -> None:
        """Key/value table (test ids, engine, date, operator...)."""
        self._kv(items, title, section or title)

    def add_settings(self, settings: dict, *, title: str = "Analysis settings",
                     section: str | None = None) -> None:
        """Key/value table of the analysis settings (window, resolution, amplitude
        convention, tacho pulses/rev, sweep rate and its estimated peak loss...)."""
        self._kv(settings, title, section or title)

    def add_provenance(self, *, files=(), model=None, parameters: dict | None = None,
                       title: str = "Provenance", section: str | None = None) -> None:
        """File hashes, model file, crankbench/Python/numpy versions, parameters.

        Parameters
        ----------
        files : sequence of path-like
            Input files (records); each is hashed (SHA-256).
        model : path-like, optional
            Model TOML; hashed too.
        parameters : dict, optional
            Command parameters to record.
        """
        import numpy as np
        import scipy

        rows = {"crankbench version": crankbench_version(),
                "python": platform.python_version(),
                "numpy / scipy": f"{np.__version__} / {scipy.__version__}",
                "report created (UTC)": self.created.isoformat()}
        for p in files or ():
            p = Path(p)
            rows[f"input {p.name}"] = (f"sha256 {file_sha256(p)}" if p.is_file()
                                       else "(not a file)")
        if model is not None:
            m = Path(model)
            rows[f"model {m.name}"] = f"sha256 {file_sha256(m)}" if m.is_file() else str(m)
        for k, v in (parameters or {}).items():
            rows[f"parameter {k}"] = v
        self._kv(rows, title, section or title)

    def _kv(self, items, title, section):
        if not isinstance(items, dict):
            raise ConfigError(f"{title}: items must be a dict, got {type(items).__name__}")
        rows = [(str(k), _fmt(v)) for k, v in items.items()]
        self._section(section).items.append(_Item("kv", title, payload={"rows": rows}))

    def add_figure(self, fig, *, title: str, caption: str = "", section: str | None = None,
                   image_format: str = "png", dpi: int = 110, close: bool = True) -> None:
        """Embed a matplotlib figure (rendered now: PNG base64 or inline SVG).

        Parameters
        ----------
        fig : matplotlib.figure.Figure
        title, caption : str
        section : str, optional
            Section title (created on first use); default "Figures".
        image_format : {'png', 'svg'}
        dpi : int
            Resolution of PNG output (the PDF fallback always uses the PNG).
        close : bool
            Close the figure afterwards (frees memory in long batch runs).
        """
        import matplotlib.pyplot as plt

        check_option(image_format, "image_format", ("png", "svg"), error=ConfigError)
        dpi = check_int(dpi, "dpi", minimum=30, error=ConfigError)
        if not hasattr(fig, "savefig"):
            raise ConfigError(f"add_figure: fig must be a matplotlib Figure, got "
                              f"{type(fig).__name__}")
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
        png = buf.getvalue()
        payload = {"png": png, "png_b64": base64.b64encode(png).decode("ascii")}
        if image_format == "svg":
            sbuf = io.StringIO()
            fig.savefig(sbuf, format="svg", bbox_inches="tight")
            svg = sbuf.getvalue()
            svg = svg[svg.find("<svg"):]  # drop the XML prolog and DOCTYPE
            payload["svg"] = svg
        if close:
            plt.close(fig)
        self._section(section or "Figures").items.append(
            _Item("figure", str(title), str(caption), payload))

    def add_table(self, frame, *, title: str, caption: str = "", section: str | None = None,
                  float_format: str = "{:.4g}", max_rows: int = 500) -> None:
        """Embed a pandas DataFrame (escaped; floats formatted; NaN shown as —)."""
        import pandas as pd

        if not isinstance(frame, pd.DataFrame):
            raise ConfigError(f"add_table: frame must be a pandas DataFrame, got "
                              f"{type(frame).__name__}")
        max_rows = check_int(max_rows, "max_rows", minimum=1, error=ConfigError)
        shown = frame.head(max_rows)
        columns = [str(c) for c in shown.columns]
        rows = [[_fmt(v, float_format) for v in row] for row in shown.itertuples(index=False)]
        note = f"first {max_rows} of {len(frame)} rows" if len(frame) > max_rows else ""
        self._section(section or title).items.append(_Item(
            "table", str(title), str(caption),
            {"columns": columns, "rows": rows, "note": note,
             "bool_columns": [c for c in columns if str(shown[c].dtype) == "bool"]}))

    def add_text(self, text: str, *, title: str = "", section: str | None = None) -> None:
        """A paragraph of plain text (escaped; blank lines separate paragraphs)."""
        paras = [p.strip() for p in str(text).split("\n\n") if p.strip()]
        self._section(section or title or "Notes").items.append(
            _Item("text", str(title), payload={"paragraphs": paras}))

    def add_limit_checks(self, checks, *, title: str = "Limit checks",
                         section: str | None = None, figures: bool = True) -> None:
        """Pass/fail table of :class:`analysis.limits.LimitCheck` rows (and their figures)."""
        checks = list(checks)
        rows = []
        for c in checks:
            d = c.as_dict()
            rows.append({"check": d["check"], "quantity": d["quantity"],
                         "value": _fmt(d["value"]), "limit": _fmt(d["limit"]),
                         "units": d["units"], "passed": bool(d["passed"]),
                         "detail": d["detail"], "source": d["source"]})
            self.add_summary(d["check"], d["passed"], d["detail"])
        sec = section or title
        self._section(sec).items.append(_Item("checks", title, payload={"rows": rows}))
        if figures:
            for c in checks:
                if c.data is not None:
                    try:
                        fig = c.plot()
                    except (TypeError, ValueError, KeyError, AttributeError) as exc:
                        log.warning("no figure for limit check %r: %s", c.name, exc)
                        continue
                    self.add_figure(fig, title=c.name, caption=c.detail, section=sec)

    def add_resonances(self, resonances, *, title: str = "Measured resonances",
                       section: str | None = None, figure: bool = True) -> None:
        """Table (and figure) of :class:`analysis.resonance.ResonanceTable`."""
        frame = resonances.to_frame()
        cols = ["order", "speed_rpm", "frequency_hz", "damping_ratio", "amplitude",
                "amplitude_corrected", "sweep_rate_rpm_per_s", "sweep_peak_loss",
                "direction", "method", "confidence"]
        sec = section or title
        units = f" Amplitudes in {resonances.units} ({resonances.amplitude_convention})." \
            if resonances.units else ""
        self.add_table(frame[[c for c in cols if c in frame]], title=title, section=sec,
                       caption="Critical speed = natural frequency × 60 / order; "
                               "amplitude_corrected restores the estimated sweep peak loss."
                               + units)
        if figure and resonances.curves:
            self.add_figure(resonances.plot(), title=f"{title}: order amplitude against speed",
                            section=sec)

    def add_comparison(self, comparison, *, title: str = "Measurement against prediction",
                       section: str | None = None, figure: bool = True) -> None:
        """Tables of a :class:`analysis.compare.CriticalComparison` with its verdict."""
        sec = section or title
        self.add_summary("critical speeds agree with the model", comparison.agrees,
                         "; ".join(comparison.flags[:3]) + (" …" if len(comparison.flags) > 3
                                                            else ""))
        self.add_table(comparison.matched, title="Matched critical speeds", section=sec,
                       caption=f"Assignment gate ±{100 * comparison.gate:g} %, speed tolerance "
                               f"±{100 * comparison.tolerance:g} %, amplitude ratio within "
                               f"[{1 / (1 + comparison.amplitude_tolerance):.2f}, "
                               f"{1 + comparison.amplitude_tolerance:.2f}].")
        self.add_table(comparison.natural_frequencies, title="Natural frequencies by mode",
                       section=sec, caption="Measured values are confidence-weighted over "
                                            "every order that excited the mode.")
        if len(comparison.unmatched_predicted):
            self.add_table(comparison.unmatched_predicted, title="Predicted criticals not found",
                           section=sec)
        if len(comparison.unmatched_measured):
            self.add_table(comparison.unmatched_measured,
                           title="Measured resonances without a predicted critical", section=sec)
        if comparison.flags:
            self.add_text("\n\n".join(comparison.flags), title="Disagreements", section=sec)
        if figure and len(comparison.matched):
            self.add_figure(comparison.plot(), title="Measured against predicted critical speeds",
                            section=sec)

    def add_html(self, markup: str, *, title: str = "", section: str | None = None) -> None:
        """Trusted raw HTML (not escaped). Must not reference the network."""
        self._section(section or title or "Notes").items.append(
            _Item("html", str(title), payload={"html": str(markup)}))

    # -- output -----------------------------------------------------------------------------
    def to_html(self) -> str:
        """The report as one self-contained HTML document."""
        from jinja2 import Environment, PackageLoader, select_autoescape

        env = Environment(loader=PackageLoader("crankbench.analysis.report", "templates"),
                          autoescape=select_autoescape(["html", "j2"]))
        template = env.get_template("report.html.j2")
        verdict = None
        judged = [p for _, p, _ in self._summary if p is not None]
        if judged:
            verdict = all(judged)
        return template.render(title=self.title, subtitle=self.subtitle,
                               created=self.created.isoformat(), version=crankbench_version(),
                               sections=self._sections, summary=self._summary,
                               verdict=verdict, n_figures=self.n_figures)

    def save(self, path, *, overwrite: bool = False, option: str = "overwrite=True") -> Path:
        """Write the report: ``.html``/``.htm`` as HTML, ``.pdf`` as PDF.

        Parameters
        ----------
        path : path-like
        overwrite : bool
            Replace an existing file. Otherwise ``FileExistsError`` names the option.
        option : str
            How the caller spells the option in messages (``--overwrite`` in the CLI).

        Returns
        -------
        Path
        """
        from crankbench.measure._atomic import atomic_path

        path = Path(path)
        suffix = path.suffix.lower()
        if suffix not in (".html", ".htm", ".pdf"):
            raise ConfigError(f"report path {str(path)!r} must end in .html or .pdf")
        if suffix == ".pdf":
            from .pdf import write_pdf

            with atomic_path(path, overwrite=overwrite, option=option) as tmp:
                write_pdf(self, tmp)
                _readable(tmp)
        else:
            text = self.to_html()
            with atomic_path(path, overwrite=overwrite, option=option) as tmp:
                tmp.write_text(text, encoding="utf-8")
                _readable(tmp)
        log.info("report written to %s", path)
        return path

    # -- for the PDF fallback ----------------------------------------------------------------
    def _iter_items(self):
        for sec in self._sections:
            yield sec, sec.items


def _readable(tmp: Path) -> None:
    """Give the temporary file (created 0600) the permissions a plain open() would."""
    import os

    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)


def _escape(text) -> str:  # pragma: no cover - convenience for templates built elsewhere
    return html.escape(str(text))
