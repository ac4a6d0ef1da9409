"""Vibrograph sensors placed on the engine model: a Record channel's ``position``/``mount``/
``location`` and ``direction`` attrs read into a point and direction of the engine frame of
:mod:`predict.mounts` (docs/DESIGN.md, "Vibrograph sensors"). A channel that cannot be placed
is listed with the reason, never guessed. Used by :func:`analysis.vibrograph.compare_vibrograph`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from crankbench.predict.errors import ConfigError, ModelError, RecordError

__all__ = ["VibroSensor", "place_sensors"]

_QUANTITIES = {"displacement": 0, "velocity": 1, "acceleration": 2}


@dataclass(frozen=True)
class VibroSensor:
    """A vibrograph channel placed on the engine block.

    Attributes
    ----------
    channel : str
    position : ndarray (3,)
        m, engine frame of :mod:`predict.mounts`.
    direction : ndarray (3,)
        Unit vector of the sensitive axis.
    quantity : {'displacement', 'velocity', 'acceleration'}
    units : str
    placed_by : str
        Which attrs placed it.
    """

    channel: str
    position: np.ndarray
    direction: np.ndarray
    quantity: str
    units: str
    placed_by: str

    def describe(self) -> str:
        d = self.direction
        axis = next((f"{'-' if d[k] < 0 else '+'}{'xyz'[k]}" for k in range(3)
                     if abs(abs(d[k]) - 1.0) < 1e-12), "[" + ", ".join(f"{v:.3g}" for v in d) + "]")
        p = ", ".join(f"{v:.3g}" for v in self.position)
        return f"{self.channel}: {self.quantity} along {axis} at ({p}) m, {self.placed_by}"


def _parse_position(value):
    """[x, y, z] from a list/array or a string 'x y z' / 'x, y, z'; None if absent."""
    if value is None:
        return None
    if isinstance(value, str):
        parts = value.replace(",", " ").replace(";", " ").split()
        try:
            value = [float(p) for p in parts]
        except ValueError:
            raise RecordError(f"position={value!r} must be three numbers x, y, z (m)") from None
    arr = np.asarray(value, dtype=float).ravel()
    if arr.size != 3 or not np.all(np.isfinite(arr)):
        raise RecordError(f"position={np.asarray(value).tolist()!r} must be three finite "
                          "numbers x, y, z (m)")
    return arr


def place_sensors(record, mounted, *, channels=None):
    """Vibrograph channels of a Record placed on the mounted engine.

    Parameters
    ----------
    record : xarray.Dataset
    mounted : predict.mounts.MountedEngine
    channels : sequence of str, optional
        Only these channels (default: every 1-D acceleration, velocity or displacement channel
        with a sample rate).

    Returns
    -------
    sensors : tuple of VibroSensor
    skipped : tuple of (channel, reason)

    Examples
    --------
    >>> import xarray as xr
    >>> from crankbench.predict.mounts import Mount, MountedEngine
    >>> eng = MountedEngine(mass=100.0, inertia=[5.0, 8.0, 8.0], cg=[0.2, 0.0, 0.1],
    ...                     mounts=[Mount(position=[x, y, 0.0], stiffness=[1e5, 1e5, 2e5],
    ...                                   name=f"m{i}{j}")
    ...                             for i, x in enumerate((0.0, 0.4))
    ...                             for j, y in enumerate((-0.2, 0.2))])
    >>> rec = xr.Dataset({
    ...     "a": ("time", np.zeros(8), {"quantity": "acceleration", "units": "m/s^2",
    ...                                 "sample_rate": 1e3, "location": "m01",
    ...                                 "direction": "z"}),
    ...     "b": ("time", np.zeros(8), {"quantity": "acceleration", "units": "m/s^2",
    ...                                 "sample_rate": 1e3, "position": "0.1 0.0 0.3",
    ...                                 "direction": "-y"}),
    ...     "c": ("time", np.zeros(8), {"quantity": "acceleration", "units": "m/s^2",
    ...                                 "sample_rate": 1e3, "direction": "z"})})
    >>> sensors, skipped = place_sensors(rec, eng)
    >>> [s.describe() for s in sensors]
    ['a: acceleration along +z at (0, 0.2, 0) m, mount m01', 'b: acceleration along -y at (0.1, 0, 0.3) m, position attr']
    >>> skipped[0][0]
    'c'
    """
    from crankbench.predict.mounts import direction_vector

    names = [str(n) for n in record.data_vars]
    if channels is not None:
        missing = [c for c in channels if c not in names]
        if missing:
            from crankbench.predict._validate import suggest

            raise RecordError(f"record has no channel {missing[0]!r}"
                              f"{suggest(missing[0], names)}; channels: {', '.join(names)}")
        names = list(channels)
    mounts = {m.name.strip().lower(): m for m in mounted.mounts if m.name}
    sensors, skipped = [], []
    for name in names:
        var = record[name]
        q = var.attrs.get("quantity")
        if q not in _QUANTITIES or var.ndim != 1 or "sample_rate" not in var.attrs:
            if channels is not None:
                skipped.append((name, f"quantity {q!r}: not a vibrograph channel (expected "
                                      "acceleration, velocity or displacement, 1-D, sampled)"))
            continue
        try:
            pos = _parse_position(var.attrs.get("position"))
        except RecordError as exc:
            skipped.append((name, str(exc)))
            continue
        placed = "position attr"
        if pos is None:
            for key in ("mount", "location"):
                label = var.attrs.get(key)
                if isinstance(label, str) and label.strip().lower() in mounts:
                    m = mounts[label.strip().lower()]
                    pos, placed = m.position, f"mount {m.name}"
                    break
        if pos is None:
            skipped.append((name, "no sensor position: give the channel attr 'position' = "
                                  "[x, y, z] (m, engine frame) or a 'location' naming a mount "
                                  f"({', '.join(m.name for m in mounted.mounts)}); for a "
                                  f"text or raw export, in a channel map: [channel.{name}] "
                                  "position = [x, y, z] or mount = \"...\", direction = "
                                  "\"z\" (--map MAP.toml)"))
            continue
        raw = var.attrs.get("direction")
        if raw is None or (isinstance(raw, str) and not raw.strip()):
            skipped.append((name, "no 'direction' attr (x, y, z or three numbers)"))
            continue
        try:
            direction = direction_vector(list(raw) if not isinstance(raw, str) else raw)
        except ModelError as exc:
            skipped.append((name, str(exc)))
            continue
        sensors.append(VibroSensor(channel=name, position=np.asarray(pos, float),
                                   direction=direction, quantity=q,
                                   units=str(var.attrs.get("units", "")), placed_by=placed))
    return tuple(sensors), tuple(skipped)
