"""Raw test-bench exports with their channel map and ground truth: what real rigs hand over.

A rig's data acquisition writes voltages, not Records: a crank wheel's pick-up (square or
magnetic, with a runt tooth, ringing and noise), a TDC mark one or two samples wide on a
drifting baseline, a pressure transducer's output with its own gain and offset, in whatever
text dialect the logger uses (comma, tab, semicolon or spaces; decimal comma; a BOM; a preamble;
names, units or no header at all) or a spreadsheet. :func:`raw_rig` writes such a file from a
closed-form shaft motion, together with the channel map that reads it
(:mod:`measure.channelmap`) and the exact truth: every wheel edge and TDC time, the speed law
and the pressure in Pa. :func:`export_table` writes any columns in any of :data:`DIALECTS`.

The speed law is a linear ramp ``n(t) = n0 + (n1 - n0) t / T``, so the shaft angle is
``θ(t) = θ0 + 2π (n0 t + (n1 - n0) t² / (2T)) / 60`` and the time of any angle is closed form.
The transducer follows the issue's example: ``V = 5 (0.00385 p + 0.115)`` with p in kPa, read
back as ``p = V × 51.948 kPa/V − 29.870 kPa``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from crankbench.predict.errors import ConfigError

from .pulses import pickup_voltage, pulse_voltage

__all__ = ["DIALECTS", "export_table", "raw_rig", "RawRig", "TRANSDUCER_SCALE",
           "TRANSDUCER_OFFSET"]

#: transducer p[kPa] = V * scale + offset for V = 5 (0.00385 p + 0.115)
TRANSDUCER_SCALE = 1.0 / (5.0 * 0.00385)
TRANSDUCER_OFFSET = -0.115 / 0.00385

#: text dialects of real loggers: delimiter, decimal mark, header form, encoding, preamble
DIALECTS = {
    "comma": dict(delimiter=",", decimal=".", header="name [unit]"),
    "tab_headerless": dict(delimiter="\t", decimal=".", header=None),
    "semicolon_decimal_comma_bom": dict(delimiter=";", decimal=",", header="names+units",
                                        encoding="utf-8-sig"),
    "whitespace_preamble": dict(delimiter=" ", decimal=".", header="names",
                                preamble=("Bench 3 data export", "Sample rate: {fs:g} Hz",
                                          "Operator: test", "")),
    "tab_decimal_comma_crlf": dict(delimiter="\t", decimal=",", header="names",
                                   line_end="\r\n", encoding="cp1252"),
    "xlsx": dict(header="names+units"),
}


def export_table(path, columns, *, delimiter=",", decimal=".", header="name [unit]",
                 encoding="utf-8", preamble=(), line_end="\n", digits=8, sample_rate=None):
    """Write columns as a text table (or an ``.xlsx`` sheet) in a logger's dialect.

    Parameters
    ----------
    path : path-like
        ``.xlsx`` writes a workbook (openpyxl), anything else text.
    columns : list of (name, unit, values)
    delimiter : str
        "," ";" "\\t" or " " (one space between fields).
    decimal : {".", ","}
    header : {"name [unit]", "names+units", "names", None}
        One row ``name [unit]``; a names row and a units row; names only; no header.
    encoding : str
        "utf-8", "utf-8-sig" (with BOM), "cp1252", ...
    preamble : sequence of str
        Free text lines above the header (``{fs}`` is replaced by ``sample_rate``).
    line_end : str
    digits : int
        Significant digits of the numbers.
    sample_rate : float, optional
        For the preamble.

    Examples
    --------
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "x.txt"
    >>> export_table(p, [("t", "s", [0.0, 0.5]), ("p", "bar", [1.25, 2.0])], delimiter=";",
    ...              decimal=",", header="names+units")
    >>> print(p.read_text())
    t;p
    s;bar
    0;1,25
    0,5;2
    <BLANKLINE>
    """
    path = Path(path)
    names = [c[0] for c in columns]
    units = [c[1] for c in columns]
    data = np.column_stack([np.asarray(c[2], float) for c in columns])
    heads = []
    if header == "name [unit]":
        heads.append([f"{n} [{u}]" for n, u in zip(names, units)])
    elif header == "names+units":
        heads += [names, units]
    elif header == "names":
        heads.append(names)
    elif header is not None:
        raise ConfigError(f"header={header!r}; expected 'name [unit]', 'names+units', 'names' "
                          "or None")
    if path.suffix.lower() == ".xlsx":
        import openpyxl

        wb = openpyxl.Workbook(write_only=True)
        ws = wb.create_sheet("Data")
        for line in preamble:
            ws.append([line.format(fs=sample_rate)] if line else [])
        for h in heads:
            ws.append(list(h))
        for row in data:
            ws.append([float(v) for v in row])
        wb.save(path)
        return
    sep = delimiter
    body = np.char.mod(f"%.{int(digits)}g", data)
    if decimal == ",":
        body = np.char.replace(body, ".", ",")
    lines = [line.format(fs=sample_rate) for line in preamble]
    lines += [sep.join(h) for h in heads]
    lines += [sep.join(r) for r in body]
    with open(path, "w", encoding=encoding, newline="") as f:
        f.write(line_end.join(lines) + line_end)


@dataclass(frozen=True)
class RawRig:
    """A raw export written by :func:`raw_rig`.

    Attributes
    ----------
    path : Path
        The data file.
    map_path : Path
        Its channel map (TOML).
    map : dict
        The same map as a dict.
    truth : dict
        ``fs``, ``time`` (s), ``speed_rpm`` (at ``time``), ``mean_speed_rpm``, ``edges``
        (wheel edge times, s), ``teeth`` (their tooth numbers, 0 the first after the gap),
        ``tdc`` (mark times, s), ``pressure_pa`` (at ``time``), ``revolutions``.
    """

    path: Path
    map_path: Path
    map: dict
    truth: dict = field(repr=False)


def _angle(t, n0, n1, duration, theta0):
    return theta0 + 2.0 * np.pi / 60.0 * (n0 * t + (n1 - n0) * t * t / (2.0 * duration))


def _time_of(theta, n0, n1, duration, theta0):
    """Inverse of :func:`_angle` (closed form)."""
    a = 2.0 * np.pi / 60.0 * (n1 - n0) / (2.0 * duration)
    b = 2.0 * np.pi / 60.0 * n0
    c = theta0 - np.asarray(theta, float)
    if abs(a) < 1e-15:
        return -c / b
    return (-b + np.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)


def raw_rig(folder, *, name="rig", dialect="tab_headerless", fs=100_000.0, duration=0.8,
            speed_rpm=(1500.0, 1500.0), pulses_per_rev=60, missing_teeth=2, runt_teeth=(57,),
            runt_level=0.11, shape="square", ringing=0.0, noise_rms=0.02, tdc=True,
            tdc_width_samples=2.0, per_cycle=False, pressure=True, time_column=False,
            theta0_deg=37.0, seed=0, map_missing_teeth=..., digits=8) -> RawRig:
    """Write a raw rig export (wheel, TDC mark, pressure transducer) with its map and truth.

    Parameters
    ----------
    folder : path-like
    name : str
        File stem.
    dialect : str
        A key of :data:`DIALECTS` (``"xlsx"`` writes a workbook).
    fs : float
        Sample rate, Hz.
    duration : float
        s.
    speed_rpm : (float, float)
        Speed at the start and the end (linear ramp).
    pulses_per_rev, missing_teeth : int
        The wheel (360, 0: an encoder).
    runt_teeth : sequence of int
        Teeth whose pulse reaches only ``runt_level`` of the swing.
    shape : {"square", "sine"}
        Hall/optical 0–5 V pulses or a magnetic pick-up's ±2 V wave.
    ringing : float
        Damping ratio of the pick-up chain (0: none), at fs / 10.
    noise_rms : float
        On every voltage, V.
    tdc : bool
        A TDC mark channel, ``tdc_width_samples`` wide, on a 0.3 V baseline drifting 0.2 V/s.
    per_cycle : bool
        The mark once per two revolutions.
    pressure : bool
        A pressure transducer channel (see the module docstring).
    time_column : bool
        Write a time column (else the map gives the sample rate).
    theta0_deg : float
        Shaft angle at t = 0 from tooth 0.
    seed : int
    map_missing_teeth : int, optional
        ``missing_teeth`` written into the map (default: the wheel's; None leaves it out).
    digits : int
        Significant digits written (a logger's resolution).

    Returns
    -------
    RawRig

    Examples
    --------
    >>> import tempfile
    >>> rig = raw_rig(tempfile.mkdtemp(), duration=0.2)
    >>> rig.path.name, len(rig.truth["tdc"]), round(rig.truth["mean_speed_rpm"], 6)
    ('rig.txt', 5, 1500.0)
    """
    if dialect not in DIALECTS:
        raise ConfigError(f"dialect={dialect!r} is not one of {', '.join(DIALECTS)}")
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    n0, n1 = (float(v) for v in speed_rpm)
    n = int(round(duration * fs))
    t = np.arange(n) / fs
    theta0 = np.radians(theta0_deg)
    theta_end = _angle(t[-1], n0, n1, duration, theta0)
    # wheel edges: tooth k (of the N pitch positions) at angle 2 pi (r + k / N)
    n_pos = int(pulses_per_rev)
    k = np.arange(int(np.floor(theta0 / (2 * np.pi) * n_pos)) - 1,
                  int(np.ceil(theta_end / (2 * np.pi) * n_pos)) + 2)
    tooth = np.mod(k, n_pos)
    keep = tooth < n_pos - int(missing_teeth)
    edges = _time_of(2 * np.pi * k[keep] / n_pos, n0, n1, duration, theta0)
    tooth = tooth[keep]
    inside = (edges > t[0]) & (edges < t[-1])
    edges, tooth = edges[inside], tooth[inside]
    from .profile import ramp, steady

    prof = steady(n0, duration=duration) if n0 == n1 else ramp(n0, n1, duration=duration)
    params = dict(pulses_per_rev=n_pos, missing_teeth=int(missing_teeth), shape=shape,
                  runt_teeth=list(runt_teeth), runt_level=runt_level, ringing=ringing,
                  ringing_hz=fs / 10.0)
    crank = pickup_voltage(edges, time=t, params=params, profile=prof)
    if shape == "sine":
        crank = 2.0 * crank
    crank = crank + noise_rms * rng.standard_normal(n)
    columns = []
    if time_column:
        columns.append(("time", "s", t))
    columns.append(("crank", "V", crank))
    span = 4 * np.pi if per_cycle else 2 * np.pi
    marks = _time_of(np.arange(np.ceil(theta0 / span), np.floor(theta_end / span) + 1) * span,
                     n0, n1, duration, theta0)
    marks = marks[(marks > 2.0 / fs) & (marks < t[-1] - 3.0 / fs)]
    if tdc:
        mark = pulse_voltage(marks, t, widths=tdc_width_samples / fs, high=4.0, low=0.0)
        mark = mark + 0.3 + 0.2 * t + noise_rms * rng.standard_normal(n)
        columns.append(("tdc", "V", mark))
    theta = _angle(t, n0, n1, duration, theta0)
    phi = np.mod(theta, 4 * np.pi) - 2 * np.pi                  # firing TDC at 2 pi
    p_kpa = 100.0 + 4900.0 * np.exp(-((phi - np.radians(12.0)) / np.radians(25.0)) ** 2)
    if pressure:
        volts = 5.0 * (0.00385 * p_kpa + 0.115) + 0.25 * noise_rms * rng.standard_normal(n)
        columns.append(("p_cyl1", "V", volts))
    spec = DIALECTS[dialect]
    ext = ".xlsx" if dialect == "xlsx" else ".txt"
    path = folder / f"{name}{ext}"
    export_table(path, columns, sample_rate=fs, digits=digits, **spec)
    cmap = {"description": f"raw rig export, dialect {dialect}", "source": {}, "channel": {}}
    if not time_column:
        cmap["source"]["sample_rate"] = float(fs)
    if dialect != "xlsx":
        cmap["source"]["delimiter"] = {",": "comma", "\t": "tab", ";": "semicolon",
                                       " ": "space"}[spec["delimiter"]]
        cmap["source"]["decimal"] = spec["decimal"]
    else:
        cmap["source"]["sheet"] = "Data"
    if time_column:
        cmap["source"]["time_column"] = 1
    col = 2 if time_column else 1
    wheel = {"column": col, "role": "wheel", "pulses_per_rev": n_pos, "keep_raw": True}
    mt = missing_teeth if map_missing_teeth is ... else map_missing_teeth
    if mt is not None:
        wheel["missing_teeth"] = int(mt)
    cmap["channel"]["crank"] = wheel
    col += 1
    if tdc:
        cmap["channel"]["tdc"] = {"column": col, "role": "tdc", "per_cycle": bool(per_cycle)}
        col += 1
    if pressure:
        cmap["channel"]["pressure"] = {"column": col, "units": "kPa", "quantity": "pressure",
                                       "scale": TRANSDUCER_SCALE, "offset": TRANSDUCER_OFFSET,
                                       "location": "cylinder 1"}
    from ..channelmap import _to_toml

    map_path = folder / f"{name}_map.toml"
    map_path.write_text(_to_toml(cmap), encoding="utf-8")
    speed = n0 + (n1 - n0) * t / duration
    truth = {"fs": fs, "time": t, "speed_rpm": speed, "mean_speed_rpm": float(speed.mean()),
             "edges": edges, "teeth": tooth, "tdc": marks, "pressure_pa": p_kpa * 1e3,
             "revolutions": float((theta_end - theta0) / (2 * np.pi))}
    return RawRig(path=path, map_path=map_path, map=cmap, truth=truth)
