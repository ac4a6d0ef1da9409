"""Report figures decimated to the pixel grid keep what is read from them: every peak of a
spiky trace survives at its own sample, the drawn envelope per pixel column is the data's,
gaps stay gaps, and the rendered image matches the full trace's within a pixel."""

import io

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from crankbench.analysis.report import Report  # noqa: E402
from crankbench.analysis.report.figures import (decimate_figure, envelope_indices,  # noqa: E402
                                                pixel_run_indices)
from crankbench.predict.errors import ConfigError  # noqa: E402


def _spiky(n=200_000, n_spikes=60, seed=0):
    """Noise on a slow sine, with single-sample spikes of either sign well above the noise."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 42.0, n)
    y = np.sin(2 * np.pi * 0.1 * t) + 0.05 * rng.standard_normal(n)
    spikes = np.sort(rng.choice(np.arange(10, n - 10), n_spikes, replace=False))
    y[spikes] += rng.choice([-1, 1], n_spikes) * rng.uniform(2.0, 9.0, n_spikes)
    return t, y, spikes


def _column_extremes(x, y, keep, n_columns, lo, hi):
    """Per column (independent loop): the data's min and max and the kept samples' min and
    max."""
    edges = lo + (hi - lo) * np.arange(n_columns + 1) / n_columns
    out = []
    for c in range(n_columns):
        inside = (x >= edges[c]) & (x < edges[c + 1]) if c < n_columns - 1 else (x >= edges[c])
        if not inside.any():
            continue
        kept = keep[inside[keep]]
        out.append((y[inside].min(), y[inside].max(), y[kept].min(), y[kept].max()))
    return np.array(out)


def _assert_spikes_drawn(x, y, spikes, keep, n_columns, lo, hi):
    column = np.clip(np.floor((x - lo) / (hi - lo) * n_columns), -1, n_columns)
    for s in spikes:
        same = column == column[s]
        kept = keep[same[keep]]
        if y[s] > 0:
            assert y[kept].max() >= y[s]
            largest = np.flatnonzero(same)[np.nanargmax(y[same])]
        else:
            assert y[kept].min() <= y[s]
            largest = np.flatnonzero(same)[np.nanargmin(y[same])]
        assert largest in keep
    assert np.isin(spikes, keep).mean() > 0.9


def test_every_spike_survives_at_its_own_sample_and_the_envelope_is_the_datas():
    t, y, spikes = _spiky()
    n_columns = 700
    keep = envelope_indices(t, y, n_columns=n_columns)
    assert keep.size <= 5 * n_columns and keep.size < t.size / 50
    # every peak is drawn: the kept samples of its column reach it, and the largest peak of
    # each column is kept at its own sample (time and value exactly); a smaller one beside it
    # in the same pixel column lies under its ink
    _assert_spikes_drawn(t, y, spikes, keep, n_columns, t[0], t[-1])
    # the drawn vertices of each column span exactly the data of that column
    ext = _column_extremes(t, y, keep, n_columns, t[0], t[-1])
    assert len(ext) == n_columns
    np.testing.assert_array_equal(ext[:, 2], ext[:, 0])
    np.testing.assert_array_equal(ext[:, 3], ext[:, 1])
    # and the segment between two columns joins neighbouring samples: the original segment
    column = np.minimum(np.floor((t - t[0]) / (t[-1] - t[0]) * n_columns), n_columns - 1)
    crossing = np.flatnonzero(np.diff(column[keep]) != 0)
    assert (np.diff(keep)[crossing] == 1).all()


def test_decreasing_axis_outside_range_and_gaps():
    t, y, spikes = _spiky(n=50_000, n_spikes=20, seed=3)
    y[20_000:20_500] = np.nan
    x = -t  # decreasing, and the columns cover only part of it
    keep = envelope_indices(x, y, n_columns=300, x_range=(-30.0, -5.0))
    _assert_spikes_drawn(x, y, spikes, keep, 300, -30.0, -5.0)
    assert keep[0] == 0 and keep[-1] == t.size - 1
    # the gap stays a gap: a NaN is drawn between the samples on either side of it
    yk = y[keep]
    before = np.flatnonzero(keep < 20_000)[-1]
    after = np.flatnonzero(keep >= 20_500)[0]
    assert np.isnan(yk[before + 1:after]).any()


def test_pixel_runs_keep_a_loop_within_a_cell_and_its_extremes():
    # a p-V-like loop travelled three times with a sharp spike: x is not monotonic
    phi = np.linspace(0.0, 6 * np.pi, 90_000)
    x, y = np.cos(phi), np.sin(phi) ** 3
    y[12_345] = 3.0
    grid = dict(n_columns=400, n_rows=300, x_range=(-1.1, 1.1), y_range=(-1.2, 3.2))
    keep = pixel_run_indices(x, y, **grid)
    assert 12_345 in keep and keep.size < x.size / 10
    # every dropped sample lies in the cell of the kept samples on either side of it
    cx = np.floor((x + 1.1) / 2.2 * 400)
    cy = np.floor((y + 1.2) / 4.4 * 300)
    nxt = keep[np.searchsorted(keep, np.arange(x.size))]
    prv = keep[np.searchsorted(keep, np.arange(x.size), side="right") - 1]
    assert (cx == cx[prv]).all() and (cy == cy[prv]).all()
    assert (cx == cx[nxt]).all() and (cy == cy[nxt]).all()


def _image(fig):
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    buf.seek(0)
    return plt.imread(buf)[..., :3].mean(axis=2)


def test_rendered_trace_matches_the_full_trace_within_a_pixel():
    t, y, _ = _spiky(n=120_000, n_spikes=40, seed=7)

    def draw():
        fig, ax = plt.subplots(figsize=(5.0, 3.0))
        ax.plot(t, y, color="k", lw=0.8, antialiased=False)
        ax.set_axis_off()
        ax.set_position([0.0, 0.0, 1.0, 1.0])
        return fig

    full, dec = draw(), draw()
    before, after = decimate_figure(dec, dpi=100)
    assert before == t.size and after < t.size / 20
    a, b = _image(full), _image(dec)
    plt.close(full)
    plt.close(dec)
    ink_a, ink_b = a < 0.5, b < 0.5
    cols = np.flatnonzero(ink_a.any(axis=0))
    assert (ink_b.any(axis=0)[cols]).all()
    rows = np.arange(a.shape[0])[:, None]
    top_a = np.where(ink_a, rows, 10**6).min(axis=0)[cols]
    top_b = np.where(ink_b, rows, 10**6).min(axis=0)[cols]
    bot_a = np.where(ink_a, rows, -1).max(axis=0)[cols]
    bot_b = np.where(ink_b, rows, -1).max(axis=0)[cols]
    # each pixel column's inked span (where the peaks show) is the other image's within one
    # pixel column: a segment inside a column may lean into the neighbouring pixel, no more
    def near(v, pick):
        p = np.pad(v, 1, mode="edge")
        return pick(np.stack([p[:-2], p[1:-1], p[2:]]), axis=0)

    assert (top_b >= near(top_a, np.min)).all() and (top_a >= near(top_b, np.min)).all()
    assert (bot_b <= near(bot_a, np.max)).all() and (bot_a <= near(bot_b, np.max)).all()
    assert np.mean(ink_a != ink_b) < 0.01


def test_lines_with_markers_and_short_lines_are_drawn_as_they_are():
    t = np.linspace(0.0, 1.0, 5000)
    fig, ax = plt.subplots()
    marked, = ax.plot(t, np.sin(40 * t), "o-", ms=1)
    short, = ax.plot(t[:500], t[:500])
    steps, = ax.plot(t, np.cos(40 * t), drawstyle="steps-post")
    long_, = ax.plot(t, np.sin(40 * t))
    before, after = decimate_figure(fig, dpi=100)
    assert len(marked.get_xdata()) == len(steps.get_xdata()) == 5000
    assert len(short.get_xdata()) == 500
    assert before == 5000 and len(long_.get_xdata()) == after < 5000
    plt.close(fig)


def test_report_svg_smaller_with_decimation_and_same_axes():
    t, y, _ = _spiky(n=100_000, n_spikes=10, seed=1)
    sizes, limits = [], []
    for decimate in (True, False):
        fig, ax = plt.subplots(figsize=(7.0, 4.0))
        ax.plot(t, y, lw=0.8)
        rep = Report("r")
        limits.append(ax.get_ylim())
        rep.add_figure(fig, title="trace", decimate=decimate)
        sizes.append(len(rep.to_html()))
    assert sizes[0] < 0.5 * sizes[1]
    assert limits[0] == limits[1]


def test_bad_inputs_name_what_was_expected():
    with pytest.raises(ConfigError, match=r"x must be monotonic \(a time or speed axis\)"):
        envelope_indices([0.0, 2.0, 1.0], [1.0, 2.0, 3.0], n_columns=4)
    with pytest.raises(ConfigError, match="x and y must be 1-D of one length"):
        envelope_indices([0.0, 1.0, 2.0], [1.0, 2.0], n_columns=4)
    with pytest.raises(ConfigError, match="x must be finite"):
        envelope_indices([0.0, np.nan, 2.0], [1.0, 2.0, 3.0], n_columns=4)
    with pytest.raises(ConfigError, match="n_columns"):
        envelope_indices([0.0, 1.0, 2.0], [1.0, 2.0, 3.0], n_columns=0)
    fig, _ = plt.subplots()
    with pytest.raises(ConfigError, match=r"dpi=0 must be positive"):
        decimate_figure(fig, dpi=0)
    plt.close(fig)


def test_dense_map_as_rasterized_svg_is_smaller_than_a_whole_png():
    # the report's choice for order maps and spectrograms: vector axes and text, the mesh as
    # an embedded image -- smaller than the whole figure as PNG at the same resolution
    rng = np.random.default_rng(2)
    sizes = {}
    for fmt in ("svg", "png"):
        fig, ax = plt.subplots(figsize=(7.5, 5.0))
        mesh = ax.pcolormesh(np.arange(40) * 0.5, np.linspace(200, 760, 120),
                             rng.random((120, 40)), rasterized=True)
        fig.colorbar(mesh, ax=ax, label="dB re max")
        ax.set_xlabel("order")
        ax.set_ylabel("engine speed (rpm)")
        rep = Report("r")
        rep.add_figure(fig, title="map", image_format=fmt)
        payload = rep._sections[0].items[0].payload
        sizes[fmt] = len(payload["svg"]) if fmt == "svg" else len(payload["png_b64"])
    assert sizes["svg"] < sizes["png"]
