"""Instrument models: seismic vibrograph / torsiograph and accelerometer, simulate and correct.

A seismic instrument is a mass on a spring and damper inside a case fixed to the machine. The
relative motion ``z`` of the mass (what the pen, mirror or transducer records) obeys

``z'' + 2 zeta omega_n z' + omega_n**2 z = -x''``

for a case motion ``x`` (linear, m; or angular, rad, for a Geiger-type seismic torsiograph).
Three instruments read it differently (``r = f / f_n``, ``s`` the Laplace variable):

* **vibrograph** (displacement meter, seismic torsiograph): soft spring, ``f_n`` well below the
  measured frequencies; reading ``-z``, so ``H(s) = s**2 / (s**2 + 2 zeta omega_n s +
  omega_n**2)`` relative to displacement, ``|H| -> 1`` for ``r >> 1``;
* **velocity pick-up** (moving coil): the same mechanics read as ``-z'``, relative to velocity
  ``H`` is the same function;
* **accelerometer**: stiff spring, ``f_n`` well above; reading ``-omega_n**2 z``, so
  ``H(s) = omega_n**2 / (s**2 + 2 zeta omega_n s + omega_n**2)`` relative to acceleration,
  ``|H| -> 1`` for ``r << 1``.

Simulation applies ``H`` in the time domain (exact discretisation of the state equations for a
piecewise-linear input, "first-order hold"; error zero for inputs linear between samples, about
``(pi f / fs)**2 / 3`` of the gain otherwise) or in the frequency domain (exact for periodic
band-limited input). Correction divides by ``H`` in the frequency domain inside the
usable band, where ``|H|`` is at least ``min_gain`` (the noise amplification is then at most
``1 / min_gain``), and removes everything outside it: below the band a vibrograph has no
information (``|H| ~ r**2``), above it an accelerometer's resonance and the anti-alias filter
rule. Within the band the correction is exact up to the FFT's periodic-extension error at the
record ends (taper or discard a few periods of the lowest frequency there).

References
----------
Liang Shoupan, *Engine dynamics* (發動機動力學), 1948, ch. 9 §§ 感振儀 (seismic instruments) and
陰極線振動儀 (cathode-ray vibration meter).
Jiaotong University, *IC-engine dynamics* (内燃机动力学), 1958, part 2 ch. 5 §1 (mechanical
and electrical torsiographs, their natural frequency and damping).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from crankbench.predict._validate import (
    check_finite_array,
    check_option,
    check_positive,
    check_range,
)
from crankbench.predict.errors import AnalysisError

__all__ = ["SeismicInstrument", "vibrograph", "torsiograph", "accelerometer",
           "velocity_pickup", "Correction", "KINDS"]

#: what each kind of instrument reads, and the quantity its transfer function refers to
KINDS = {
    "displacement": "vibrograph / seismic torsiograph: reads displacement above f_n",
    "velocity": "moving-coil pick-up: reads velocity above f_n",
    "acceleration": "accelerometer: reads acceleration below f_n",
}


@dataclass(frozen=True)
class Correction:
    """A signal corrected for an instrument's response.

    Attributes
    ----------
    data : numpy.ndarray
        Corrected signal, in the measured quantity's units.
    band_hz : tuple of float
        Frequencies kept, Hz (everything outside was removed).
    max_gain : float
        Largest noise amplification applied, ``max 1/|H|`` in the band.
    end_effect_s : float
        Length at each record end where the FFT's periodic extension makes the result
        unreliable unless the record holds whole periods (about two periods of the band's
        lowest frequency for a vibrograph, whose inverse is an integrator); discard it.
    """

    data: np.ndarray
    band_hz: tuple
    max_gain: float
    end_effect_s: float = 0.0

    def to_frame(self):
        """One-row table of the correction's band, gain and end effect."""
        import pandas as pd

        return pd.DataFrame([{"band_low_hz": self.band_hz[0], "band_high_hz": self.band_hz[1],
                              "max_gain": self.max_gain, "end_effect_s": self.end_effect_s,
                              "samples": self.data.size}])

    def plot(self, ax=None, *, fs=None):
        """The corrected signal (against time if ``fs`` is given); returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots() if ax is None else (ax.figure, ax)
        x = np.arange(self.data.size) / fs if fs else np.arange(self.data.size)
        ax.plot(x, self.data)
        ax.set_xlabel("time (s)" if fs else "sample")
        ax.set_title(f"corrected in {self.band_hz[0]:.3g}-{self.band_hz[1]:.3g} Hz")
        return fig


@dataclass(frozen=True)
class SeismicInstrument:
    """Single-degree-of-freedom seismic instrument.

    Parameters
    ----------
    natural_frequency : float
        Undamped natural frequency of the seismic system, Hz.
    damping_ratio : float
        Fraction of critical damping (0.6-0.7 flattens the response best).
    kind : {"displacement", "velocity", "acceleration"}
        What the instrument reads (see :data:`KINDS`).
    sensitivity : float
        Output per unit of the measured quantity in the flat band (e.g. V per m/s^2); 1 keeps
        the output in the measured quantity's SI units.

    Examples
    --------
    >>> acc = accelerometer(natural_frequency=30_000.0, damping_ratio=0.02)
    >>> round(abs(complex(acc.frf(3000.0))), 5)      # 1 / |1 - r**2 + 2j zeta r| at r = 0.1
    1.01009
    """

    natural_frequency: float
    damping_ratio: float
    kind: str = "displacement"
    sensitivity: float = 1.0

    def __post_init__(self):
        check_positive(self.natural_frequency, "natural_frequency")
        check_range(self.damping_ratio, "damping_ratio", 0.0, 10.0)
        check_option(self.kind, "kind", KINDS)
        check_positive(self.sensitivity, "sensitivity")

    # -- response ------------------------------------------------------------------------
    def frf(self, freq_hz):
        """Complex frequency response: output per unit of the measured quantity.

        Parameters
        ----------
        freq_hz : array_like
            Frequencies, Hz.

        Returns
        -------
        numpy.ndarray of complex
        """
        f = np.asarray(freq_hz, dtype=float)
        r = f / self.natural_frequency
        den = 1.0 - r**2 + 2j * self.damping_ratio * r
        # H(j omega) of s**2 / (s**2 + 2 zeta omega_n s + omega_n**2) is -r**2 / den
        num = -(r**2) if self.kind in ("displacement", "velocity") else np.ones_like(r)
        return self.sensitivity * num / den

    def usable_band(self, *, tolerance=0.05, fs=None):
        """Frequency band where the uncorrected reading is within ``tolerance`` of true.

        Parameters
        ----------
        tolerance : float
            Allowed amplitude error of the raw reading, fraction (0.05 = ±5 %).
        fs : float, optional
            Sample rate, Hz; caps the band at 0.45 fs.

        Returns
        -------
        tuple of float
            ``(f_low, f_high)`` in Hz (``f_high`` is inf if unbounded).

        Examples
        --------
        >>> lo, hi = vibrograph(natural_frequency=5.0, damping_ratio=0.65).usable_band()
        >>> round(lo, 2), hi
        (6.94, inf)
        """
        tolerance = check_range(tolerance, "tolerance", 0.0, 1.0, inclusive=(False, False))
        fn = self.natural_frequency
        r = np.geomspace(1e-4, 1e4, 200_001)
        with np.errstate(divide="ignore", invalid="ignore"):  # undamped: infinite at r = 1
            gain = np.abs(self.frf(r * fn)) / self.sensitivity
        ok = np.isfinite(gain) & (np.abs(gain - 1.0) <= tolerance)
        if self.kind == "acceleration":
            bad = np.flatnonzero(~ok)
            hi = r[bad[0] - 1] * fn if bad.size else np.inf
            lo = 0.0
        else:
            bad = np.flatnonzero(~ok)
            lo = r[bad[-1] + 1] * fn if bad.size else 0.0
            hi = np.inf
        if fs is not None:
            hi = min(hi, 0.45 * check_positive(fs, "fs"))
        return float(lo), float(hi)

    def correction_band(self, *, fs, min_gain=0.1):
        """Band where the response can be divided out: ``|H| / sensitivity >= min_gain``.

        Returns ``(f_low, f_high)`` in Hz, capped at 0.45 ``fs``.
        """
        min_gain = check_range(min_gain, "min_gain", 0.0, 1.0, inclusive=(False, True))
        fs = check_positive(fs, "fs")
        fn, z = self.natural_frequency, self.damping_ratio
        if self.kind == "acceleration":
            # |H| falls below min_gain above resonance at r**2 ~ 1 + 1/min_gain
            r = np.geomspace(1.0, 1e4, 100_001)
            with np.errstate(divide="ignore", invalid="ignore"):
                gain = np.abs(1.0 / (1 - r**2 + 2j * z * r))
            idx = np.flatnonzero(gain < min_gain)
            hi = r[idx[0]] * fn if idx.size else np.inf
            return 0.0, float(min(hi, 0.45 * fs))
        r = np.geomspace(1e-4, 1.0, 100_001)
        with np.errstate(divide="ignore", invalid="ignore"):
            gain = np.abs(r**2 / (1 - r**2 + 2j * z * r))
        idx = np.flatnonzero(gain >= min_gain)
        lo = r[idx[0]] * fn if idx.size else fn
        return float(lo), float(0.45 * fs)

    # -- simulate ------------------------------------------------------------------------
    def simulate(self, signal, *, fs, method="foh"):
        """The instrument's reading of a true signal.

        Parameters
        ----------
        signal : array_like
            True motion, uniformly sampled, SI units: the quantity the instrument reads
            (displacement, velocity or acceleration).
        fs : float
            Sample rate, Hz.
        method : {"foh", "fft"}
            ``"foh"``: the state equations of the seismic mass discretised exactly for an input
            varying linearly between samples (first-order hold), run as a causal recursive
            filter from rest, start transient included. The linear hold smooths the input: the
            gain error at frequency ``f`` is about ``(pi f / fs)**2 / 3`` relative for an
            accelerometer (0.4 % at fs/28), far less for a vibrograph whose direct feed-through
            dominates. ``"fft"``: multiplies the spectrum by :meth:`frf`, exact for a
            band-limited input that is periodic over the record (steady state, no transient).

        Returns
        -------
        numpy.ndarray
            Instrument output (``sensitivity`` times the reading).

        Examples
        --------
        >>> import numpy as np
        >>> fs, f = 20_000.0, 50.0
        >>> t = np.arange(80_000) / fs
        >>> vib = vibrograph(natural_frequency=5.0, damping_ratio=0.1)
        >>> y = vib.simulate(np.sin(2 * np.pi * f * t), fs=fs)
        >>> round(float(np.abs(y[-2000:]).max()), 3)      # r = 10: 100 / |1 - 100 + 2j|
        1.01
        """
        from scipy.signal import cont2discrete, lfilter

        x = check_finite_array(signal, "signal", ndim=1, min_length=2)
        fs = check_positive(fs, "fs")
        check_option(method, "method", ("foh", "fft"))
        if method == "fft":
            f = np.fft.rfftfreq(x.size, 1.0 / fs)
            return np.fft.irfft(np.fft.rfft(x) * self.frf(f), x.size)
        wn = 2 * np.pi * self.natural_frequency
        z = self.damping_ratio
        den = [1.0, 2 * z * wn, wn**2]
        num = [1.0, 0.0, 0.0] if self.kind != "acceleration" else [wn**2]
        b, a, _ = cont2discrete((num, den), 1.0 / fs, method="foh")
        b = np.atleast_1d(np.squeeze(b))
        return self.sensitivity * lfilter(b, a, x)

    # -- correct -------------------------------------------------------------------------
    def correct(self, signal, *, fs, min_gain=0.1, band=None, taper=0.05):
        """Recover the measured quantity from the instrument's output (deconvolution).

        The output's spectrum is divided by ``H(f)`` inside the band and set to zero outside it
        (raised-cosine edges over ``taper`` of the band's width in log-frequency avoid ringing).

        Parameters
        ----------
        signal : array_like
            Instrument output.
        fs : float
            Sample rate, Hz.
        min_gain : float
            Lowest ``|H| / sensitivity`` divided out (noise amplification at most ``1 /
            min_gain``); sets the default band (:meth:`correction_band`).
        band : tuple of float, optional
            ``(f_low, f_high)`` in Hz, overriding the default band.
        taper : float
            Fraction of each band edge (in octaves of the band) given a cosine taper; 0 = brick
            wall.

        Returns
        -------
        Correction
            Corrected signal, band used, largest gain applied and the end length to discard.
            Components outside the band are lost; inside it the error is the FFT's end effect
            (periodic extension, confined to ``end_effect_s`` at each end) only.

        Examples
        --------
        >>> import numpy as np
        >>> fs = 10_000.0
        >>> t = np.arange(20_000) / fs
        >>> true = np.sin(2 * np.pi * 12.3 * t)                  # 12.3 Hz, near f_n
        >>> vib = vibrograph(natural_frequency=10.0, damping_ratio=0.3)
        >>> reading = vib.simulate(np.tile(true, 2), fs=fs)[20_000:]   # settled
        >>> out = vib.correct(reading, fs=fs)
        >>> round(out.band_hz[0], 2), round(out.end_effect_s, 3)
        (3.04, 0.657)
        >>> k = int(out.end_effect_s * fs)
        >>> bool(np.max(np.abs(out.data[k:-k] - true[k:-k])) < 0.02)
        True
        """
        y = check_finite_array(signal, "signal", ndim=1, min_length=8)
        fs = check_positive(fs, "fs")
        lo, hi = self.correction_band(fs=fs, min_gain=min_gain) if band is None else band
        lo, hi = float(lo), float(hi)
        if not (0.0 <= lo < hi):
            raise AnalysisError(f"band={band!r} must be (f_low, f_high) with 0 <= f_low < f_high")
        taper = check_range(taper, "taper", 0.0, 0.5)
        n = y.size
        # no zero padding: padding would add a step at the record end that the inverse filter
        # (an integrator for a vibrograph) spreads over the whole record
        nfft = n
        spec = np.fft.rfft(y, nfft)
        f = np.fft.rfftfreq(nfft, 1.0 / fs)
        with np.errstate(divide="ignore", invalid="ignore"):
            h = self.frf(f)
        weight = _band_weight(f, lo, hi, taper)
        weight[~np.isfinite(h) | (h == 0)] = 0.0
        keep = weight > 0
        inv = np.zeros_like(h)
        inv[keep] = weight[keep] / h[keep]
        out = np.fft.irfft(spec * inv, nfft)[:n]
        gain = float(np.max(np.abs(inv[keep]))) * self.sensitivity if keep.any() else 0.0
        edge = 2.0 / lo if (lo > 0 and self.kind != "acceleration") else 2.0 / min(hi, 0.45 * fs)
        return Correction(data=out, band_hz=(lo, hi), max_gain=gain,
                          end_effect_s=float(min(edge, 0.5 * n / fs)))

    def to_frame(self, freq_hz=None):
        """FRF table: ``freq_hz``, ``gain``, ``phase_deg`` (default 200 points, 0.01-100 f_n)."""
        import pandas as pd

        f = np.geomspace(0.01, 100, 200) * self.natural_frequency if freq_hz is None else \
            np.asarray(freq_hz, dtype=float)
        h = self.frf(f) / self.sensitivity
        return pd.DataFrame({"freq_hz": f, "gain": np.abs(h), "phase_deg": np.degrees(np.angle(h))})

    def plot(self, ax=None):
        """Gain against frequency ratio; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots() if ax is None else (ax.figure, ax)
        frame = self.to_frame()
        ax.loglog(frame.freq_hz / self.natural_frequency, frame.gain)
        ax.set_xlabel("f / f_n")
        ax.set_ylabel("|H|")
        ax.set_title(f"{self.kind} instrument, f_n={self.natural_frequency:g} Hz, "
                     f"zeta={self.damping_ratio:g}")
        return fig


def _band_weight(f, lo, hi, taper):
    w = ((f >= lo) & (f <= hi)).astype(float)
    if taper <= 0:
        return w
    # cosine ramps over `taper` octaves-of-band inside each edge, in log frequency
    with np.errstate(divide="ignore"):
        lf = np.log2(np.maximum(f, 1e-300))
    width = taper * max(np.log2(hi / lo) if lo > 0 and np.isfinite(hi) else 8.0, 1.0)
    if lo > 0:
        ramp = (lf - np.log2(lo)) / width
        inner = (ramp >= 0) & (ramp < 1)
        w[inner] *= 0.5 - 0.5 * np.cos(np.pi * ramp[inner])
    if np.isfinite(hi):
        ramp = (np.log2(hi) - lf) / width
        inner = (ramp >= 0) & (ramp < 1)
        w[inner] *= 0.5 - 0.5 * np.cos(np.pi * ramp[inner])
    return w


def vibrograph(*, natural_frequency, damping_ratio, sensitivity=1.0):
    """Seismic displacement meter (Geiger vibrograph): reads displacement above ``f_n``.

    Examples
    --------
    >>> v = vibrograph(natural_frequency=4.0, damping_ratio=0.6)
    >>> round(abs(complex(v.frf(40.0))), 4)
    1.0028
    """
    return SeismicInstrument(natural_frequency, damping_ratio, "displacement", sensitivity)


def torsiograph(*, natural_frequency, damping_ratio, sensitivity=1.0):
    """Seismic torsiograph (Geiger type): a flywheel on a soft torsion spring; reads angular
    displacement (rad) above ``f_n``, same dynamics as :func:`vibrograph`.

    Examples
    --------
    >>> tg = torsiograph(natural_frequency=2.0, damping_ratio=0.5)
    >>> round(abs(complex(tg.frf(2.0))), 3)          # at resonance: 1 / (2 zeta)
    1.0
    """
    return SeismicInstrument(natural_frequency, damping_ratio, "displacement", sensitivity)


def velocity_pickup(*, natural_frequency, damping_ratio, sensitivity=1.0):
    """Moving-coil velocity pick-up: reads velocity above ``f_n``.

    Examples
    --------
    >>> round(abs(complex(velocity_pickup(natural_frequency=10.0,
    ...                                   damping_ratio=0.7).frf(100.0))), 4)
    1.0002
    """
    return SeismicInstrument(natural_frequency, damping_ratio, "velocity", sensitivity)


def accelerometer(*, natural_frequency, damping_ratio=0.02, sensitivity=1.0):
    """Piezoelectric/strain-gauge accelerometer: reads acceleration below ``f_n``.

    Examples
    --------
    >>> a = accelerometer(natural_frequency=25_000.0)
    >>> lo, hi = a.usable_band(tolerance=0.05)
    >>> round(hi / 25_000.0, 3)                     # about 0.22 f_n for +5 %
    0.218
    """
    return SeismicInstrument(natural_frequency, damping_ratio, "acceleration", sensitivity)
