"""The test report: built by ``Report.add_*`` calls, saved as self-contained HTML or PDF.

One HTML source serves the screen and paper: print CSS sets A4 pages with page numbers
("page n of N"), keeps headings with their figures and tables, wraps wide tables (the widest on
landscape pages) and repeats table headers. Every figure is rendered when it is added — inline
vector SVG by default (text kept as text), PNG on request — so the saved HTML needs no network
and no side files. Tables are pandas DataFrames printed under human headers with units and the
digits of each quantity (:mod:`analysis.report.columns`). Every check is a three-state
:class:`analysis.verdict.Verdict` (pass / fail / inconclusive) naming its rule and its data; the
overall verdict is their :func:`analysis.verdict.combine`. The PDF is typeset from the same HTML
by WeasyPrint. ``save(path)`` writes atomically and refuses to replace an existing file unless
``overwrite=True``.
"""

from __future__ import annotations

import base64
import datetime as _dt
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
    """SHA-256 of a file's bytes (hex): :func:`measure.provenance.sha256_of`.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "x.bin"
    >>> _ = p.write_bytes(b"abc")
    >>> file_sha256(p)[:16]
    'ba7816bf8f01cfea'
    """
    # one implementation: measure.provenance caches it per file identity, so a record the
    # pipeline already hashed for its provenance is not read a second time for the report
    from crankbench.measure.provenance import sha256_of

    return sha256_of(path)


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
    >>> print(rep.n_figures, out.read_text().count("<svg"))
    1 1
    """

    def __init__(self, title: str = "crankbench test report", *, subtitle: str = ""):
        self.title = str(title)
        self.subtitle = str(subtitle)
        self.created = _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0)
        self._sections: list[_Section] = []
        self._verdicts: list = []

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
    def add_verdict(self, verdict) -> None:
        """One check in the verdict box (:class:`analysis.verdict.Verdict`)."""
        from ..verdict import Verdict

        if not isinstance(verdict, Verdict):
            raise ConfigError(f"add_verdict: expected an analysis.verdict.Verdict, got "
                              f"{type(verdict).__name__}")
        self._verdicts.append(verdict)

    def add_verdicts(self, verdicts) -> None:
        """Several checks in the verdict box."""
        for v in verdicts:
            self.add_verdict(v)

    def add_summary(self, label: str, passed: bool | None, detail: str = "", *,
                    rule: str = "—") -> None:
        """A line of the verdict box from a boolean: True pass, False fail, None an
        informational line that does not count (prefer :meth:`add_verdict`)."""
        from ..verdict import Verdict

        detail = str(detail)
        if passed is None:
            self._verdicts.append(Verdict.inconclusive(str(label), rule=rule, basis=detail or "—",
                                                       reason="for information",
                                                       required=False))
        else:
            self._verdicts.append(Verdict.from_bool(str(label), bool(passed), rule=rule,
                                                    basis=detail or "—", reason=detail))

    @property
    def verdict(self):
        """The overall verdict of the checks added (:func:`analysis.verdict.combine`)."""
        from ..verdict import combine

        return combine(self._verdicts)

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
                   image_format: str = "svg", dpi: int = 150, close: bool = True,
                   decimate: bool = True) -> None:
        """Embed a matplotlib figure (rendered now: inline vector SVG, or PNG base64).

        Long traces are first decimated to the output's pixel grid by their min/max envelope
        per pixel column (:func:`analysis.report.figures.decimate_figure`: every peak kept at
        its own sample; each pixel column's ink matches within one pixel column), which cuts
        the rendering time and the SVG's size of figures with long time or speed traces.

        Parameters
        ----------
        fig : matplotlib.figure.Figure
        title, caption : str
        section : str, optional
            Section title (created on first use); default "Figures".
        image_format : {'svg', 'png'}
            SVG (default) keeps lines and text vector; artists marked ``rasterized`` (dense
            colour maps) are embedded as images inside it at ``dpi``.
        dpi : int
            Resolution of PNG output and of rasterized artists.
        close : bool
            Close the figure afterwards (frees memory in long batch runs).
        decimate : bool
            Decimate long traces to the pixel grid at ``dpi`` first (changes ``fig``'s lines
            in place); False draws every sample.
        """
        import matplotlib.pyplot as plt

        check_option(image_format, "image_format", ("png", "svg"), error=ConfigError)
        dpi = check_int(dpi, "dpi", minimum=30, error=ConfigError)
        if not hasattr(fig, "savefig"):
            raise ConfigError(f"add_figure: fig must be a matplotlib Figure, got "
                              f"{type(fig).__name__}")
        if decimate:
            from .figures import decimate_figure

            decimate_figure(fig, dpi=dpi)
        payload = {}
        if image_format == "png":
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
            png = buf.getvalue()
            payload = {"png": png, "png_b64": base64.b64encode(png).decode("ascii")}
        else:
            import matplotlib

            sbuf = io.StringIO()
            with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": "crankbench"}):
                fig.savefig(sbuf, format="svg", bbox_inches="tight", dpi=dpi)
            svg = sbuf.getvalue()
            svg = svg[svg.find("<svg"):]  # drop the XML prolog and DOCTYPE
            # unique ids per figure: several inline SVGs share one document
            n = self.n_figures + 1
            svg = svg.replace('id="', f'id="f{n}-').replace("url(#", f"url(#f{n}-") \
                .replace('xlink:href="#', f'xlink:href="#f{n}-')
            payload["svg"] = svg
        if close:
            plt.close(fig)
        self._section(section or "Figures").items.append(
            _Item("figure", str(title), str(caption), payload))

    def add_table(self, frame, *, title: str, caption: str = "", section: str | None = None,
                  amplitude_units: str = "", columns: dict | None = None, max_rows: int = 500,
                  row_classes=None, filter_label: str = "", float_format=None) -> None:
        """Embed a pandas DataFrame under human headers with units (NaN shown as —).

        Parameters
        ----------
        frame : pandas.DataFrame
        title, caption, section : str
        amplitude_units : str
            SI units of the amplitude columns (rad is shown in mdeg, m/s in mm/s, Pa in MPa).
        columns : dict, optional
            ``{name: (header, unit, kind)}`` overrides of :data:`analysis.report.columns.COLUMNS`.
        max_rows : int
        row_classes : sequence of str, optional
            A CSS class per row; rows of class ``minor`` are hidden by the table's filter.
        filter_label : str
            With ``row_classes``: a check box of this label that hides the minor rows on screen
            (CSS only; printed pages show the state of the check box).
        """
        import pandas as pd

        from .columns import format_table

        if not isinstance(frame, pd.DataFrame):
            raise ConfigError(f"add_table: frame must be a pandas DataFrame, got "
                              f"{type(frame).__name__}")
        max_rows = check_int(max_rows, "max_rows", minimum=1, error=ConfigError)
        shown = frame.head(max_rows)
        headers, rows = format_table(shown, amplitude_units=amplitude_units, columns=columns)
        note = f"first {max_rows} of {len(frame)} rows" if len(frame) > max_rows else ""
        classes = list(row_classes)[:len(rows)] if row_classes is not None else [""] * len(rows)
        self._table_count = getattr(self, "_table_count", 0) + 1
        self._section(section or title).items.append(_Item(
            "table", str(title), str(caption),
            {"columns": headers, "rows": rows, "note": note, "classes": classes,
             "filter": str(filter_label), "id": f"t{self._table_count}",
             "wide": len(headers) > 9}))

    def add_text(self, text: str, *, title: str = "", section: str | None = None) -> None:
        """A paragraph of plain text (escaped; blank lines separate paragraphs)."""
        paras = [p.strip() for p in str(text).split("\n\n") if p.strip()]
        self._section(section or title or "Notes").items.append(
            _Item("text", str(title), payload={"paragraphs": paras}))

    def add_limit_checks(self, checks, *, title: str = "Limit checks",
                         section: str | None = None, figures: bool = True) -> None:
        """Table of :class:`analysis.limits.LimitCheck` rows (verdict, worst value and limit
        in display units, rule and clause, basis), their verdicts, and their figures."""
        from .columns import amplitude_display, format_value

        checks = list(checks)
        rows = []
        for c in checks:
            unit, scale = amplitude_display(c.units)
            unit = "" if unit == "1" else unit
            value = format_value(c.value, "sig3", scale=scale)
            limit = format_value(c.limit, "sig3", scale=scale)
            rows.append({"check": c.name, "quantity": c.quantity,
                         "value": f"{value} {unit}".strip() if value != "—" else "—",
                         "limit": f"{limit} {unit}".strip() if limit != "—" else "—",
                         "status": c.status, "detail": c.detail, "source": c.source,
                         "basis": c.basis})
            self.add_verdict(c.verdict)
        sec = section or title
        self._section(sec).items.append(_Item("checks", title, payload={"rows": rows}))
        if figures:
            drawn = []
            for c in checks:
                if c.data is not None and not any(c.data is d for d in drawn):
                    drawn.append(c.data)
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
                       amplitude_units=resonances.units,
                       caption="Critical speed = natural frequency × 60 / order; the "
                               "sweep-corrected amplitude restores the estimated sweep peak "
                               "loss." + units)
        if figure and resonances.curves:
            self.add_figure(resonances.plot(), title=f"{title}: order amplitude against speed",
                            section=sec)

    def add_steady_orders(self, table, *, title: str = "Steady-state order table",
                          section: str | None = None) -> None:
        """The steady-state order table of a constant-speed record
        (:func:`analysis.steady.steady_orders`): amplitude and phase per order and steady
        segment with their 1-σ uncertainty."""
        cols = ["segment", "speed_rpm", "revolutions", "order", "amplitude",
                "amplitude_uncertainty", "phase_deg", "phase_uncertainty_deg"]
        units = str(table.attrs.get("units", ""))
        self.add_table(table[[c for c in cols if c in table]], title=title,
                       section=section or title, amplitude_units=units,
                       caption=f"Constant-speed record: each order's steady-state amplitude "
                               f"({table.attrs.get('amplitude_convention', 'peak')}) and phase "
                               f"over whole revolutions, ±1 σ from the noise beside the orders "
                               f"(no sweep, so no sweep rate and no resonance crossing). "
                               f"Phases referred to {table.attrs.get('phase_reference', '')}.")

    def add_comparison(self, comparison, *, title: str = "Measurement against prediction",
                       section: str | None = None, figure: bool = True, amplitude_units="",
                       predicted=None, verdict=None) -> None:
        """One critical-speed table (predicted and measured side by side, a filter hiding the
        weak criticals), the natural frequencies by mode, the disagreements, and the verdict
        of a :class:`analysis.compare.CriticalComparison`."""
        import pandas as pd

        sec = section or title
        self.add_verdict(verdict if verdict is not None else comparison.verdict())
        table = critical_speed_table(comparison, predicted)
        classes = ["" if s else "minor" for s in table["significant"]]
        n_minor = classes.count("minor")
        self.add_table(
            table, title="Critical speeds: predicted and measured", section=sec,
            amplitude_units=amplitude_units, row_classes=classes,
            filter_label="significant criticals only",
            caption=f"One row per predicted critical in the measured range and per measured "
                    f"resonance without one. Status: matched, not found, or unexplained. "
                    f"Assignment gate ±{100 * comparison.gate:g} %, speed tolerance "
                    f"±{100 * comparison.tolerance:g} %, amplitude ratio within "
                    f"[{1 / (1 + comparison.amplitude_tolerance):.2f}, "
                    f"{1 + comparison.amplitude_tolerance:.2f}]; only significant criticals "
                    "are judged."
                    + (f" The filter hides {n_minor} weak criticals (predicted amplitude under "
                       "5 % of the largest); untick it in the HTML report to list them."
                       if n_minor else ""))
        self.add_table(comparison.natural_frequencies, title="Natural frequencies by mode",
                       section=sec, caption="Measured values are confidence-weighted over "
                                            "every order that excited the mode.")
        if comparison.flags:
            self.add_text("\n\n".join(comparison.flags), title="Disagreements", section=sec)
        if figure and len(comparison.matched):
            self.add_figure(comparison.plot(), title="Measured against predicted critical speeds",
                            section=sec)
        del pd

    def add_html(self, markup: str, *, title: str = "", section: str | None = None) -> None:
        """Trusted raw HTML (not escaped). Must not reference the network."""
        self._section(section or title or "Notes").items.append(
            _Item("html", str(title), payload={"html": str(markup)}))

    # -- output -----------------------------------------------------------------------------
    def to_html(self) -> str:
        """The report as one self-contained HTML document (screen and print)."""
        from jinja2 import Environment, PackageLoader, select_autoescape

        env = Environment(loader=PackageLoader("crankbench.analysis.report", "templates"),
                          autoescape=select_autoescape(["html", "j2"]))
        template = env.get_template("report.html.j2")
        return template.render(title=self.title, subtitle=self.subtitle,
                               created=self.created.isoformat(), version=crankbench_version(),
                               sections=self._sections, verdicts=self._verdicts,
                               overall=self.verdict if self._verdicts else None,
                               n_figures=self.n_figures)

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
        log.debug("report written to %s", path)
        return path


def critical_speed_table(comparison, predicted=None):
    """The one critical-speed table: every predicted critical in range beside its measured
    resonance (or 'not found'), then the measured resonances no critical explains.

    Columns: mode, order, predicted and measured speed (rpm), deviation (%), predicted and
    measured frequency (Hz), predicted and measured amplitude, their ratio, damping ratio,
    confidence, significant, status.
    """
    import pandas as pd

    from ..compare import not_judged_reason

    cols = ["mode", "order", "speed_rpm_predicted", "speed_rpm_measured", "deviation_pct",
            "frequency_hz_predicted", "frequency_hz_measured", "amplitude_predicted",
            "amplitude_measured", "amplitude_ratio", "damping_ratio", "confidence",
            "significant", "status"]
    rows = []
    unjudged = comparison.settings.get("amplitudes_not_judged") is not None
    for _, r in comparison.matched.iterrows():
        d = {c: r.get(c) for c in cols if c in r}
        ok = bool(r.speed_ok) and (unjudged or bool(r.amplitude_ok))
        judged = "matched (speed; amplitude not judged: load not stated)" if unjudged \
            else "matched"
        d["status"] = (judged if ok else "matched, outside tolerance") if r.significant \
            else "matched, not judged: " + not_judged_reason(predicted, r["mode"], r["order"])
        rows.append(d)
    for _, r in comparison.unmatched_predicted.iterrows():
        rows.append({"mode": r["mode"], "order": r["order"],
                     "speed_rpm_predicted": r["speed_rpm"],
                     "frequency_hz_predicted": r.get("frequency_hz"),
                     "amplitude_predicted": r.get("amplitude"),
                     "significant": bool(r["significant"]),
                     "status": r.get("status") or "not found" if r["significant"] else
                     "not found, not judged: " + not_judged_reason(predicted, r["mode"],
                                                                   r["order"])})
    for _, r in comparison.unmatched_measured.iterrows():
        rows.append({"mode": None, "order": r["order"], "speed_rpm_measured": r["speed_rpm"],
                     "frequency_hz_measured": r.get("frequency_hz"),
                     "amplitude_measured": r.get("amplitude"),
                     "damping_ratio": r.get("damping_ratio"),
                     "confidence": r.get("confidence"), "significant": True,
                     "status": "no predicted critical"})
    table = pd.DataFrame(rows, columns=cols)
    if len(table):
        key = table["speed_rpm_predicted"].fillna(table["speed_rpm_measured"])
        table = table.assign(_k=key).sort_values("_k").drop(columns="_k").reset_index(drop=True)
        table["mode"] = table["mode"].astype(object)
    return table


def _readable(tmp: Path) -> None:
    """Give the temporary file (created 0600) the permissions a plain open() would."""
    import os

    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)


def _escape(text) -> str:  # pragma: no cover - convenience for templates built elsewhere
    return html.escape(str(text))
