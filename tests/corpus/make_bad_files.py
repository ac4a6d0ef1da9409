"""Generate the bad-record corpus ``tests/corpus/bad/records/`` (issue 10, file formats; issues
14 and 19: real-rig text and spreadsheet exports, duplicate columns, external links).

Every file is small (< 100 kB) and broken in one documented way: zero length, truncated,
wrong magic bytes, header/body mismatch, NaN/inf runs, clipping, non-monotonic or duplicated
time, sample rate 0 or negative, unknown unit strings, plus a few CSV/WAV-specific faults. Each one is
read in ``tests/measure/test_bad_files.py`` with the asserted message (or, where the data is
usable in part, the masked result and its warning).

Run from the repository root::

    python tests/corpus/make_bad_files.py [--overwrite]

Deterministic apart from the MDF file-history timestamp asammdf writes.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from crankbench.measure import io  # noqa: E402
from crankbench.measure.record import make_record  # noqa: E402

OUT = Path(__file__).resolve().parent / "bad" / "records"
FS = 1000.0
N = 500


def base_record(acc=None, *, pulses=None):
    """A valid 0.5 s record: 1 kHz accelerometer, 20 Hz speed, 20 tacho edges."""
    rng = np.random.default_rng(7)
    if acc is None:
        acc = rng.normal(0.0, 1.0, N).astype(np.float32)
    if pulses is None:
        pulses = 0.0125 + np.arange(20) * 0.025
    return make_record({
        "acc": dict(data=acc, sample_rate=FS, units="m/s^2", quantity="acceleration",
                    location="block", direction="z"),
        "speed": dict(data=np.linspace(150.0, 160.0, 10), sample_rate=20.0, units="rad/s",
                      quantity="rotational_speed"),
        "tacho": dict(data=pulses, units="s", quantity="pulse_times", pulses_per_rev=1),
    }, start_time="2026-01-01T00:00:00+00:00", allow_nonfinite=True)


def _write(rec, path):
    io.write(rec, path, overwrite=True)


def _truncate(src: Path, dst: Path, fraction: float = 0.6):
    data = src.read_bytes()
    dst.write_bytes(data[: int(len(data) * fraction)])


def _h5_patch(path: Path, func):
    import h5py

    with h5py.File(path, "r+") as f:
        func(f)


def make_all(out: Path) -> list[Path]:
    """Write every corpus file into ``out``; return their paths."""
    import h5py
    import nptdms
    import soundfile as sf
    from asammdf import MDF, Signal

    out.mkdir(parents=True, exist_ok=True)
    made: list[Path] = []
    tmp = Path(tempfile.mkdtemp())
    try:
        good = {}
        for ext in (".h5", ".csv", ".mf4", ".tdms", ".uff", ".wav"):
            good[ext] = tmp / f"good{ext}"
            _write(base_record(), good[ext])

        def add(name) -> Path:
            p = out / name
            made.append(p)
            return p

        # zero length
        for ext in (".h5", ".csv", ".mf4", ".tdms", ".uff", ".wav"):
            add(f"empty{ext}").write_bytes(b"")

        # truncated (crashed logger): first 60 % of a valid file
        for ext in (".h5", ".csv", ".mf4", ".tdms", ".uff", ".wav"):
            _truncate(good[ext], add(f"truncated{ext}"))
        shutil.copy(str(good[".wav"]) + ".json", str(out / "truncated.wav") + ".json")

        # wrong magic bytes
        add("text_named.h5").write_text("time [s],acc [g]\n0,1\n0.001,2\n")
        shutil.copy(good[".mf4"], add("mdf_named.tdms"))
        shutil.copy(good[".h5"], add("hdf5_named.csv"))
        add("random_bytes.wav").write_bytes(np.random.default_rng(3).bytes(256))
        add("random_bytes.uff").write_bytes(b"\x00\x01garbage" * 20)

        # header/body mismatch
        shutil.copy(good[".h5"], add("length_mismatch.h5"))
        _h5_patch(out / "length_mismatch.h5", lambda f: f["dims/time"].attrs.__setitem__(
            "length", N + 100))
        shutil.copy(good[".h5"], add("missing_channel.h5"))
        _h5_patch(out / "missing_channel.h5", lambda f: f.attrs.__setitem__(
            "channel_order", json.dumps(["acc", "speed", "tacho", "ghost"])))
        text = good[".csv"].read_text().replace('"n":500', '"n":400', 1)
        add("declared_rows.csv").write_text(text)
        shutil.copy(good[".wav"], add("sidecar_channels.wav"))
        side = json.loads(Path(str(good[".wav"]) + ".json").read_text())
        extra_col = dict(side["channels"][0], name="acc2")
        Path(str(out / "sidecar_channels.wav") + ".json").write_text(
            json.dumps({**side, "channels": side["channels"] + [extra_col]}))
        shutil.copy(good[".wav"], add("sidecar_rate.wav"))
        Path(str(out / "sidecar_rate.wav") + ".json").write_text(
            json.dumps({**side, "sample_rate": 2000.0}))
        with nptdms.TdmsWriter(str(add("wf_samples.tdms"))) as w:
            w.write_segment([nptdms.ChannelObject("g", "acc", np.zeros(N), properties={
                "unit_string": "g", "wf_increment": 1e-3, "wf_start_offset": 0.0,
                "wf_samples": 2 * N})])
        data = good[".uff"].read_bytes()
        cut = data.rfind(b"    -1\n    58")
        add("missing_dataset.uff").write_bytes(data[:cut])

        # NaN / inf runs (usable in part)
        acc = np.random.default_rng(7).normal(0.0, 1.0, N).astype(np.float32)
        nan_acc = acc.copy()
        nan_acc[100:120] = np.nan
        _write(base_record(nan_acc), add("nan_run.h5"))
        inf_acc = acc.copy()
        inf_acc[200:205] = np.inf
        inf_acc[300] = -np.inf
        _write(base_record(inf_acc), add("inf_run.csv"))
        _write(base_record(nan_acc), add("nan_run.mf4"))

        # non-monotonic and duplicated time
        t = np.arange(N) / FS
        back = t.copy()
        back[250] = back[248]
        dup = t.copy()
        dup[250] = dup[249]
        for name, tt in (("nonmonotonic_time.csv", back), ("duplicated_time.csv", dup)):
            rows = "\n".join(f"{a!r},{b!r}" for a, b in zip(tt.tolist(), acc.tolist()))
            add(name).write_text("time [s],acc [g]\n" + rows + "\n")
        shutil.copy(good[".h5"], add("nonmonotonic_time.h5"))

        def explicit_back(f):
            g = f["dims/time"]
            g.attrs["kind"] = "explicit"
            g.create_dataset("values", data=back)
        _h5_patch(out / "nonmonotonic_time.h5", explicit_back)
        shutil.copy(good[".h5"], add("duplicated_pulses.h5"))

        def dup_pulse(f):
            d = f["channels/tacho"]
            v = d[...]
            v[5] = v[4]
            d[...] = v
        _h5_patch(out / "duplicated_pulses.h5", dup_pulse)

        # sample rate 0 / negative
        shutil.copy(good[".h5"], add("rate_zero.h5"))
        _h5_patch(out / "rate_zero.h5", lambda f: f["dims/time"].attrs.__setitem__(
            "sample_rate", 0.0))
        text = good[".csv"].read_text().replace('"sample_rate":1000.0', '"sample_rate":-1000.0',
                                                1)
        add("rate_negative.csv").write_text(text)
        with nptdms.TdmsWriter(str(add("rate_zero.tdms"))) as w:
            w.write_segment([nptdms.ChannelObject("g", "acc", np.zeros(N), properties={
                "unit_string": "g", "wf_increment": 0.0, "wf_start_offset": 0.0,
                "wf_samples": N})])
        shutil.copy(good[".wav"], add("rate_zero.wav"))
        Path(str(out / "rate_zero.wav") + ".json").write_text(
            json.dumps({**side, "sample_rate": 0.0}))

        # unknown unit strings
        rows = "\n".join(f"{a!r},{b!r}" for a, b in zip(t.tolist(), acc.tolist()))
        add("unknown_unit.csv").write_text("time [s],acc [gee]\n" + rows + "\n")
        shutil.copy(good[".h5"], add("unknown_unit.h5"))
        _h5_patch(out / "unknown_unit.h5", lambda f: f["channels/acc"].attrs.__setitem__(
            "units", "furlong/fortnight^2"))
        with nptdms.TdmsWriter(str(add("unknown_unit.tdms"))) as w:
            w.write_segment([nptdms.ChannelObject("g", "acc", np.zeros(N), properties={
                "unit_string": "Volts?", "wf_increment": 1e-3, "wf_start_offset": 0.0,
                "wf_samples": N})])
        mdf = MDF(version="4.10")
        mdf.append([Signal(np.zeros(N), t, name="acc", unit="gee")])
        saved = mdf.save(str(tmp / "unknown_unit.mf4"), overwrite=True)
        mdf.close()
        shutil.copy(saved, add("unknown_unit.mf4"))
        data = good[".uff"].read_bytes().replace(b"m/s^2               ", b"mm/ss               ")
        add("unknown_unit.uff").write_bytes(data)
        shutil.copy(good[".wav"], add("unknown_unit.wav"))
        cols = [dict(side["channels"][0], units="m/s/s")]
        Path(str(out / "unknown_unit.wav") + ".json").write_text(
            json.dumps({**side, "channels": cols}))

        # clipped (amplifier / ADC saturation; usable in part, flagged on read)
        tt = np.arange(N) / FS
        sine = 1.3 * np.sin(2 * np.pi * 10.0 * tt)
        _write(base_record(np.clip(sine, -0.8, 0.8).astype(np.float32)), add("clipped.h5"))
        dither = np.random.default_rng(11).normal(0.0, 3.0, N)   # ADC noise, codes rms
        pcm = np.clip(np.round(sine * 32767 + dither), -32768, 32767).astype(np.int16)
        sf.write(str(add("clipped_pcm.wav")), pcm, 1000, subtype="PCM_16", format="WAV")
        Path(str(out / "clipped_pcm.wav") + ".json").write_text(json.dumps({
            "crankbench_sidecar": 1, "attrs": {"start_time": "2026-01-01T00:00:00+00:00"},
            "channels": [{"name": "acc", "units": "g", "scale": 2.0}]}))

        # format-specific faults
        add("no_time_column.csv").write_text("acc [g],vel [mm/s]\n1,2\n3,4\n")
        add("non_numeric.csv").write_text("time [s],acc [g]\n0,1\n0.001,overload\n")
        add("header_only.csv").write_text("time [s],acc [g]\n")
        add("no_unit.csv").write_text("time [s],acc\n0,1\n0.001,2\n")
        sf.write(str(add("no_sidecar.wav")), np.zeros((100, 2), np.float32), 1000,
                 subtype="FLOAT", format="WAV")
        shutil.copy(good[".wav"], add("bad_sidecar_json.wav"))
        Path(str(out / "bad_sidecar_json.wav") + ".json").write_text('{"channels": [')
        with h5py.File(add("foreign_layout.h5"), "w") as f:
            f.create_dataset("acc", data=np.zeros(10))
        made += make_import_faults(out, good[".h5"])
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return made


def make_import_faults(out: Path, good_h5: Path) -> list[Path]:
    """Faults of real-rig exports and of record files (issues 14 and 19): text whose dialect
    or header cannot be inferred, duplicate column names, ragged rows, legacy and empty
    workbooks, an HDF5 record whose channel is an external link."""
    import h5py
    import openpyxl

    made = []

    def add(name):
        made.append(out / name)
        return out / name

    add("duplicate_columns.csv").write_text("time [s],acc [g],acc [g]\n0,1,2\n0.001,2,3\n")
    add("headerless.txt").write_text("0\t0.5\t1.5\n0.001\t0.6\t1.4\n0.002\t0.7\t1.3\n")
    add("ambiguous_delimiter.txt").write_text("0,5\n0,6\n0,7\n")
    add("ragged_rows.csv").write_text("time [s],acc [g]\n0,1\n0.001,2,3\n0.002,3\n")
    add("bad_cell_decimal_comma.csv").write_text(
        "Zeit [s];Druck [bar]\n0;1,5\n0,001;1,6\n0,002;---\n0,003;1,8\n")
    add("legacy.xls").write_bytes(b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1" + bytes(56))
    wb = openpyxl.Workbook()
    wb.active.append(["notes only", "no numbers"])
    wb.save(add("no_numbers.xlsx"))
    shutil.copy(good_h5, add("external_link.h5"))
    with h5py.File(out / "external_link.h5", "r+") as f:
        del f["channels/acc"]
        f["channels/acc"] = h5py.ExternalLink("elsewhere.h5", "/channels/acc")
    return made


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--overwrite", action="store_true", help="replace existing files")
    args = parser.parse_args(argv)
    if args.out.exists() and any(args.out.iterdir()) and not args.overwrite:
        print(f"make_bad_files: {args.out} is not empty; pass --overwrite to regenerate",
              file=sys.stderr)
        return 1
    if args.out.exists() and args.overwrite:
        for p in args.out.iterdir():
            p.unlink()
    made = make_all(args.out)
    total = sum(p.stat().st_size for p in args.out.iterdir())
    print(f"{len(made)} bad record files ({total / 1e3:.0f} kB) in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
