"""Helpers shared by the format modules: attribute cleaning, clocks, regular-time detection."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import xarray as xr

from crankbench.predict.errors import RecordError

from ..record import is_pulse_dim, plain_variable, time_coordinate
from ..units import QUANTITIES, SI_UNITS, sensitivity_to_si, to_si_owned

__all__ = ["clean_attr", "clean_attrs", "regular_start", "channel_meta", "dims_of",
           "si_channel", "build_dataset", "select", "meta_json", "jsonable_attrs",
           "refuse_truth", "META_KEYS", "REGULAR_KEY", "refuse_external_links"]

#: Channel attrs carried through every format's metadata slot.
META_KEYS = ("units", "quantity", "sample_rate", "location", "direction", "sensitivity",
             "sensitivity_units", "pulses_per_rev", "missing_teeth")


def clean_attr(value):
    """Convert numpy/h5py attribute values to plain Python (str, int, float, bool, list)."""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    if isinstance(value, np.ndarray):
        if value.ndim == 0:
            return clean_attr(value[()])
        if value.dtype.kind in "SOU":
            return [clean_attr(v) for v in value.tolist()]
        return value
    return value


def jsonable_attrs(attrs: dict) -> dict:
    """Attrs as JSON-ready values (string keys, numpy arrays as lists) for formats that keep
    our metadata in a text slot (MDF comments, TDMS properties, UFF ids, WAV sidecar)."""
    out = {}
    for key, value in attrs.items():
        value = clean_attr(value)
        out[str(key)] = value.tolist() if isinstance(value, np.ndarray) else value
    return out


def refuse_truth(path, truth) -> None:
    """Raise RecordError if ground truth is given for a format that cannot store it."""
    if truth is not None:
        raise RecordError(f"{path}: ground truth can only be stored in .h5/.hdf5/.nc records")


def clean_attrs(attrs) -> dict:
    """``clean_attr`` over a mapping."""
    return {str(k): clean_attr(v) for k, v in dict(attrs).items()}


def regular_start(t: np.ndarray, fs: float) -> float | None:
    """Return ``t[0]`` if ``t`` equals ``time_coordinate(len(t), fs, t[0])`` exactly, else None."""
    t = np.asarray(t, dtype=np.float64)
    if t.size == 0:
        return 0.0
    if np.array_equal(t, time_coordinate(t.size, fs, float(t[0]))):
        return float(t[0])
    return None


def dims_of(record: xr.Dataset) -> dict[str, list[str]]:
    """Channel names grouped by their dim, in record order."""
    out: dict[str, list[str]] = {}
    for name, var in record.data_vars.items():
        out.setdefault(str(var.dims[0]), []).append(str(name))
    return out


def channel_meta(var: xr.DataArray, *, dim: str | None = None) -> dict:
    """The Record attrs of ``var`` as a JSON-able dict (plus ``dim``)."""
    meta = {}
    for k, v in var.attrs.items():
        v = clean_attr(v)
        if isinstance(v, np.ndarray):
            v = v.tolist()
        meta[str(k)] = v
    if dim is not None:
        meta["dim"] = dim
    return meta


def meta_json(meta: dict) -> str:
    """Compact JSON of a metadata dict."""
    return json.dumps(meta, separators=(",", ":"), sort_keys=False, allow_nan=True)


def si_channel(name: str, values, meta: dict, *, file: str):
    """Convert one channel read from a file to SI; returns ``(values, attrs)``.

    ``values`` is owned by the reader (freshly read): it is scaled in place.

    ``meta`` holds the file's metadata for the channel: ``units`` (any known spelling),
    optional ``quantity``, ``sensitivity`` (+ ``sensitivity_units``) and the other Record keys.
    """
    unit = meta.get("units")
    if unit is None or unit == "":
        raise RecordError(f"{file}: channel {name!r} has no unit in the file; expected one of "
                          f"{', '.join(SI_UNITS)} or a usual spelling (g, mm/s, rpm, bar...)")
    try:
        values, si, hint = to_si_owned(values, str(unit), channel=name)
    except RecordError as exc:
        raise RecordError(f"{file}: {exc}") from None
    attrs = {k: meta[k] for k in META_KEYS if k in meta and meta[k] is not None}
    attrs.update({k: v for k, v in meta.items() if k not in META_KEYS and k != "dim"
                  and v is not None and not k.startswith("_")})
    attrs["units"] = si
    quantity = meta.get("quantity") or hint
    if quantity is None or quantity == "sensitivity":
        quantity = "pulse_times" if si == "s" and "pulses_per_rev" in meta else "other"
    if quantity not in QUANTITIES:
        raise RecordError(f"{file}: channel {name!r} has unknown quantity {quantity!r}; "
                          f"expected one of {', '.join(QUANTITIES)}")
    attrs["quantity"] = quantity
    if "sensitivity" in attrs and "sensitivity_units" in attrs:
        try:
            value, su = sensitivity_to_si(float(attrs["sensitivity"]),
                                          str(attrs["sensitivity_units"]), channel=name)
        except RecordError as exc:
            raise RecordError(f"{file}: {exc}") from None
        attrs["sensitivity"], attrs["sensitivity_units"] = value, su
    for key in ("pulses_per_rev", "missing_teeth"):
        if key in attrs:
            try:
                attrs[key] = int(attrs[key])
            except (TypeError, ValueError):
                raise RecordError(f"{file}: channel {name!r}: {key}={attrs[key]!r}; expected "
                                  "an integer") from None
    if "sample_rate" in attrs:
        try:
            attrs["sample_rate"] = float(attrs["sample_rate"])
        except (TypeError, ValueError):
            raise RecordError(f"{file}: channel {name!r}: sample_rate={attrs['sample_rate']!r} "
                              "is not a number (expected Hz > 0)") from None
    return values, attrs


#: Dataset.encoding key where a reader lists the time dims it built as start + i/fs;
#: ``measure.io.read`` pops it and skips their step-by-step scan.
REGULAR_KEY = "crankbench_regular_dims"


def build_dataset(channels: list[tuple[str, str, np.ndarray, dict]], coords: dict,
                  attrs: dict, *, regular=()) -> xr.Dataset:
    """Assemble ``[(name, dim, values, attrs)]`` and ``{dim: time array}`` into a Dataset.

    ``regular`` names the dims whose coordinate was built by ``time_coordinate``.
    """
    data_vars = {}
    for name, dim, values, vattrs in channels:
        data_vars[name] = plain_variable(dim, values, vattrs)
    # a pandas Index built without copying: xarray would otherwise copy and re-check the array
    coord_vars = {dim: (dim, pd.Index(np.asarray(t, dtype=np.float64), copy=False),
                        {"units": "s", "long_name": "time from record start"})
                  for dim, t in coords.items() if not is_pulse_dim(dim)}
    ds = xr.Dataset(data_vars, coords=coord_vars, attrs=attrs)
    if regular:
        ds.encoding[REGULAR_KEY] = sorted(set(regular) & set(coord_vars))
    return ds


def select(names: list[str], channels, *, file: str) -> list[str]:
    """Names to load: all, or ``channels`` checked against ``names`` (did-you-mean)."""
    if channels is None:
        return list(names)
    from crankbench.predict._validate import suggest

    wanted = [channels] if isinstance(channels, str) else list(channels)
    for c in wanted:
        if c not in names:
            raise RecordError(f"{file}: no channel {c!r}{suggest(c, names)}; channels: "
                              f"{', '.join(names)}")
    return wanted


def refuse_external_links(path, *, file=None, h5file=None) -> None:
    """Refuse an HDF5 file holding external links or virtual datasets (data in other files).

    A record must hold its own data: following a link would read (and hash-attribute to this
    record) another file, possibly one that changed or that the user never named.

    Parameters
    ----------
    path : path-like
        The file.
    file : str, optional
        Its name in messages (default ``str(path)``).
    h5file : h5py.File or h5py.h5f.FileID, optional
        The file already open (read-only): checked without opening it again.

    Raises
    ------
    RecordError
        Naming the object, the file and path it points to.
    """
    import h5py

    file = file or str(path)
    if h5file is None:
        with h5py.File(path, "r") as f:
            return refuse_external_links(path, file=file, h5file=f)
    if not _linked_or_virtual(h5file.id if isinstance(h5file, h5py.File) else h5file):
        return  # the usual file: one walk through h5py's low-level API, no Python objects
    f = h5file if isinstance(h5file, h5py.File) else h5py.File(h5file)  # to name the links
    found = []

    def visit(name, link):
        if isinstance(link, h5py.ExternalLink):
            found.append(f"{name!r} is an external link to {link.filename}:{link.path}")
            return True
        # only datasets can be virtual: ask the object's type without opening groups
        if (isinstance(link, h5py.HardLink)
                and h5py.h5o.get_info(f.id, name.encode()).type == h5py.h5o.TYPE_DATASET):
            obj = f[name]
            if obj.is_virtual:
                sources = sorted({s.file_name for s in obj.virtual_sources()})
                found.append(f"{name!r} is a virtual dataset reading {', '.join(sources)}")
                return True
        return None

    f.visititems_links(visit)
    if found:
        raise RecordError(f"{file}: HDF5 object {found[0]}; a record must hold its own "
                          "data (external links and virtual datasets are not followed)")


def _linked_or_virtual(fid) -> bool:
    """True if the open HDF5 file ``fid`` (``h5py.h5f.FileID``) holds an external link or a
    virtual dataset; a walk over its links by h5py's low-level API (about 4x faster than
    ``visititems_links``, which builds a Python link object per entry)."""
    import h5py

    hit = []

    def visit(name, info):
        if info.type == h5py.h5l.TYPE_EXTERNAL:
            hit.append(name)
            return 1
        if (info.type == h5py.h5l.TYPE_HARD
                and h5py.h5o.get_info(fid, name).type == h5py.h5o.TYPE_DATASET
                and h5py.h5d.open(fid, name).get_create_plist().get_layout()
                == h5py.h5d.VIRTUAL):
            hit.append(name)
            return 1
        return None

    fid.links.visit(visit, info=True)
    return bool(hit)
