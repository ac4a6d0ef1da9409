"""BLAS thread limits around small solves (predict._threads): the limit holds inside the
block, is restored after it, and large problems keep their threads."""

import numpy as np
from threadpoolctl import threadpool_info

from crankbench.predict._threads import SMALL_SIZE, limit_blas, single_threaded_blas


def _blas_threads():
    return {lib["filepath"]: lib["num_threads"] for lib in threadpool_info()
            if lib["user_api"] == "blas"}


def test_limit_holds_inside_and_is_restored():
    import scipy.linalg  # noqa: F401 - load SciPy's BLAS as well as numpy's

    before = _blas_threads()
    with limit_blas():
        assert set(_blas_threads().values()) == {1}
        with limit_blas(2):              # nested: the inner setting, then the outer again
            assert set(_blas_threads().values()) <= {1, 2}
        assert set(_blas_threads().values()) == {1}
    assert _blas_threads() == before
    with limit_blas(size=SMALL_SIZE + 1):
        assert _blas_threads() == before


def test_decorator_limits_and_passes_results_through():
    seen = []

    @single_threaded_blas
    def solve(a, b):
        seen.append(set(_blas_threads().values()))
        return np.linalg.solve(a, b)

    np.testing.assert_allclose(solve(2 * np.eye(3), np.ones(3)), 0.5)
    assert seen == [{1}] and solve.__name__ == "solve"


def test_public_small_solvers_run_single_threaded(monkeypatch):
    """vold_kalman's banded solves and find_resonances' fits (issue 21: 6-10x slower under
    threaded BLAS) run with one BLAS thread: the inner solver records the setting it sees."""
    import crankbench.analysis.resonance.finder as finder
    import crankbench.analysis.vkf as vkf
    import xarray as xr

    seen = {}

    def spy(module, name):
        inner = getattr(module, name)

        def wrapped(*args, **kwargs):
            seen.setdefault(name, set()).update(_blas_threads().values())
            return inner(*args, **kwargs)

        monkeypatch.setattr(module, name, wrapped)

    spy(vkf, "_solve_block")
    spy(finder, "_modal_fit")
    fs = 400.0
    t = np.arange(0, 4, 1 / fs)
    rpm = 600 + 60 * t
    x = np.cos(2 * np.pi * np.cumsum(rpm / 60) / fs)
    vkf.vold_kalman(x, fs=fs, speed_rpm=rpm, orders=[1], bandwidth_hz=2.0)
    speed = np.linspace(100.0, 300.0, 800)          # order 6 through a 20 Hz mode, ζ = 0.03
    r = 6 * speed / 60 / 20.0
    h = 1 / (1 - r ** 2 + 2j * 0.03 * r)
    track = xr.Dataset({"amplitude": (("order", "time"), np.abs(h)[None], {"units": "rad"}),
                        "phase": (("order", "time"), np.angle(h)[None], {"units": "rad"})},
                       coords={"order": [6.0], "rpm": ("time", speed),
                               "time": ("time", np.arange(speed.size) * 0.05)})
    assert len(finder.find_resonances(track)) == 1
    assert seen == {"_solve_block": {1}, "_modal_fit": {1}}
