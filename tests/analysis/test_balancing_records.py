"""Two-plane balancing from measurement records (``crankbench balance RUN.h5 ... --channel``).

The bearing responses are NOT made with the influence model of ``predict.rotor_balance`` (that
would be circular): they come from the finite-element rotor of ``predict.lateral``
(``Rotor.unbalance_response``, Friswell et al., *Dynamics of Rotating Machines* §5.10) for the
two-disk rotor of ``sample_data/rotors/two_disk.toml`` at 2400 rpm with a known unbalance in the
two disk planes. Each complex response X becomes the time signal ``x(t) = Re(X e^{iΩt})`` (+
noise) started at a different shaft angle in every run, with a once-per-rev tacho or a
``rotational_speed`` channel; the command must recover the correction masses ``-U``.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from crankbench.analysis.cli import main
from crankbench.measure import write
from crankbench.measure.record import make_record

ROOT = Path(__file__).resolve().parents[2]
RADIUS = 0.14
RPM = 2400.0
OMEGA = RPM * np.pi / 30
PLANES = (0.5, 1.0)
PROBES = (0.0, 1.5)
U = np.array([0.0124 * np.exp(1j * np.radians(43)), 0.0087 * np.exp(1j * np.radians(212))])
TRIAL = 0.010
FS = 1024.0
DURATION = 5.0


@pytest.fixture(scope="module")
def responses():
    from crankbench.predict.lateral.toml import load_rotor

    rotor = load_rotor(ROOT / "sample_data" / "rotors" / "two_disk.toml").rotor

    def resp(masses):
        items = [(p, abs(m) * RADIUS, np.angle(m)) for p, m in zip(PLANES, masses)]
        return rotor.unbalance_response([OMEGA], items, probes=list(PROBES)).response[0, :, 0]

    return {"initial": resp(U), "trial1": resp(U + [TRIAL, 0]), "trial2": resp(U + [0, TRIAL])}


def _record(x_complex, *, start_angle, mark_angle=0.3, noise=0.0, tacho=True, seed=0):
    """Record of the bearing x vibrations; the shaft is at ``start_angle`` at t = 0."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(DURATION * FS)) / FS
    chans = {}
    for name, z in zip(("bearing_a", "bearing_b"), x_complex):
        x = np.real(z * np.exp(1j * (OMEGA * t + start_angle)))
        x = x + noise * abs(z) * rng.standard_normal(t.size)
        chans[name] = dict(data=x, sample_rate=FS, units="m")
    if tacho:  # edges where the shaft angle passes mark_angle
        k = np.arange(np.ceil((start_angle - mark_angle) / (2 * np.pi)),
                      (OMEGA * DURATION + start_angle - mark_angle) / (2 * np.pi))
        chans["tacho"] = dict(data=(2 * np.pi * k + mark_angle - start_angle) / OMEGA,
                              quantity="pulse_times", units="s", pulses_per_rev=1)
    else:
        chans["speed"] = dict(data=np.full(50, RPM), sample_rate=10.0, units="rpm")
    return make_record(chans)


def _run(tmp_path, capsys, responses, extra=(), **kw):
    paths = []
    starts = [kw.pop(f"start{i}", 0.0) for i in range(3)]
    for i, name in enumerate(("initial", "trial1", "trial2")):
        start = starts[i]
        p = tmp_path / f"{name}.h5"
        write(_record(responses[name], start_angle=start, seed=i, **kw), p, overwrite=True)
        paths.append(str(p))
    capsys.readouterr()
    code = main(["balance", *paths, "--channel", "bearing_a", "--channel", "bearing_b",
                 "--trial", "2:1:0.010@0", "--trial", "trial2:2:0.010@0", "--json", *extra])
    assert code == 0
    return json.loads(capsys.readouterr().out)


def _corrections(out):
    c = out["corrections"]
    rows = c if isinstance(c, list) else [dict(zip(c, v)) for v in zip(*c.values())]
    return np.array([r["mass_kg"] * np.exp(1j * np.radians(r["angle_deg"])) for r in rows])


def test_exact_records_with_tacho_recover_unbalance(tmp_path, capsys, responses):
    """Exact signals, each run started at another shaft angle: phase must come from the tacho."""
    out = _run(tmp_path, capsys, responses, start0=0.0, start1=2.0, start2=-1.1)
    corr = _corrections(out)
    assert np.max(np.abs(corr + U) / np.abs(U)) < 0.01
    ph = out["phasors"]
    ph = ph if isinstance(ph, list) else [dict(zip(ph, v)) for v in zip(*ph.values())]
    amps = np.array([r["amplitude"] for r in ph])
    want = np.abs(np.concatenate([responses[n] for n in ("initial", "trial1", "trial2")]))
    assert np.allclose(amps, want, rtol=1e-3)
    # phase against the mark at 0.3 rad: x = |X| cos(θ + ∠X + 0.3)
    phases = np.array([r["phase_deg"] for r in ph])
    want_ph = np.degrees(np.angle(np.concatenate(
        [responses[n] for n in ("initial", "trial1", "trial2")]) * np.exp(0.3j)))
    assert np.allclose(np.angle(np.exp(1j * np.radians(phases - want_ph))), 0, atol=2e-3)
    assert all(r["phase_reference"] == "1/rev tacho 'tacho'" for r in ph)


def test_speed_channel_records_start_at_same_angle(tmp_path, capsys, responses):
    """Without a tacho the reference is the record start (triggered acquisition)."""
    out = _run(tmp_path, capsys, responses, tacho=False)
    assert np.max(np.abs(_corrections(out) + U) / np.abs(U)) < 0.01


def test_noisy_records_within_few_percent(tmp_path, capsys, responses):
    """White noise of 10 % of each channel's amplitude per sample: corrections within 3 %.

    The reported block scatter matches white-noise theory: a Hann-windowed block of N samples
    gives a complex amplitude error of RMS ``σ sqrt(4 ENBW / N)`` (ENBW = 1.5 bins), here
    N = 16 revolutions × 1024/40 samples.
    """
    noise = 0.1
    out = _run(tmp_path, capsys, responses, noise=noise, start1=1.0, start2=4.0)
    assert np.max(np.abs(_corrections(out) + U) / np.abs(U)) < 0.03
    ph = out["phasors"]
    ph = ph if isinstance(ph, list) else [dict(zip(ph, v)) for v in zip(*ph.values())]
    rel = np.array([r["std"] / r["amplitude"] for r in ph])
    want = noise * np.sqrt(4 * 1.5 / (16 * FS / (RPM / 60)))
    assert np.all((rel > want / 1.6) & (rel < want * 1.6)), (rel, want)


def test_mixed_phase_references_refused(tmp_path, capsys, responses):
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    write(_record(responses["initial"], start_angle=0.0), a)
    write(_record(responses["trial1"], start_angle=0.0, tacho=False), b)
    assert main(["balance", str(a), str(b), "--channel", "bearing_a",
                 "--trial", "b:1:0.01@0"]) == 2
    assert "different phase references" in capsys.readouterr().err


def test_bad_trial_and_channel_named(tmp_path, capsys, responses):
    a = tmp_path / "a.h5"
    write(_record(responses["initial"], start_angle=0.0), a)
    assert main(["balance", str(a), "--channel", "bearing_a", "--trial", "a:0.01"]) == 2
    assert "RUN:PLANE:MASS_KG@ANGLE_DEG" in capsys.readouterr().err
    assert main(["balance", str(a), "--channel", "bearing_x", "--trial", "1:1:0.01@0"]) == 2
    err = capsys.readouterr().err
    assert "bearing_x" in err and "bearing_a" in err
    assert main(["balance", str(a), "--channel", "bearing_a", "--trial", "7:1:0.01@0"]) == 2
    assert "1..1" in capsys.readouterr().err


def test_sample_records(capsys):
    """The shipped records (sample_data/balance/generate.py, 5 % noise) give the known
    corrections -U within 2 % and a check run that passes ISO 21940-11 G 6.3."""
    d = ROOT / "sample_data" / "balance" / "records"
    capsys.readouterr()
    assert main(["balance", *(str(d / f"{n}.h5") for n in
                              ("initial", "trial_plane1", "trial_plane2", "check")),
                 "--channel", "bearing_a", "--channel", "bearing_b", "--trial", "2:1:0.010@0",
                 "--trial", "3:2:0.010@0", "--check", "check", "--radius", "0.14",
                 "--rotor-mass", "50", "--max-speed", "3000", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert np.max(np.abs(_corrections(out) + U) / np.abs(U)) < 0.02
    assert out["iso_21940_11"]["passed"] is True


def test_run_up_excluded_from_average():
    """A run-up 1800 -> 2400 rpm in the first 2 s (response ∝ speed², unbalance force) is left
    out: only blocks at the steady speed are averaged; the tacho edges follow the varying speed.
    """
    from crankbench.analysis.balancing import first_order_phasors

    t = np.arange(int(8 * FS)) / FS
    rpm = 1800 + 600 * np.minimum(t / 2.0, 1.0)
    om = rpm * np.pi / 30
    phi = np.concatenate([[0.0], np.cumsum(0.5 * (om[1:] + om[:-1]) / FS)])
    x = np.array([3e-5 * np.exp(0.7j), 5e-5 * np.exp(-2.1j)])
    start, mark = 1.3, 0.4
    chans = {n: {"data": np.real(z * (rpm / RPM) ** 2 * np.exp(1j * (phi + start))),
                 "sample_rate": FS, "units": "m"} for n, z in zip("ab", x)}
    ang = phi + start - mark
    k = np.arange(np.ceil(ang[0] / (2 * np.pi)), ang[-1] / (2 * np.pi))
    chans["key"] = {"data": np.interp(2 * np.pi * k, ang, t), "quantity": "pulse_times",
                    "units": "s", "pulses_per_rev": 1}
    df = first_order_phasors(make_record(chans), ["a", "b"], speed_tolerance=0.005)
    assert np.allclose(df.amplitude, np.abs(x), rtol=1e-3)
    dphi = np.radians(df.phase_deg) - np.angle(x) - mark
    assert np.allclose(np.angle(np.exp(1j * dphi)), 0.0, atol=1e-3)
    assert np.allclose(df.rpm, RPM, rtol=1e-6)
    assert (df["std"] / df.amplitude < 1e-3).all()
