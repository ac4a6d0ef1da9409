"""Start-up stays light: importing the packages, the main entry points' first use and
``crankbench --help`` leave the heavy optional libraries unimported (they load on first use of
the feature that needs them). Timing against numpy + scipy.signal + xarray is the bench's
``startup`` suite; this checks what is imported, which does not depend on the machine."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from crankbench.analysis.bench.suite_startup import HEAVY

ROOT = Path(__file__).resolve().parents[1]


def _heavy_loaded(code):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    probe = code + f"\nimport sys\nprint(sorted(m for m in {HEAVY!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return out.stdout.strip().splitlines()[-1]


@pytest.mark.parametrize("code", [
    "import crankbench.measure, crankbench.analysis, crankbench.predict",
    "from crankbench.measure import read\n"
    "from crankbench.analysis import order_track, analyse, find_resonances\n"
    "from crankbench.predict.torsion import chain",
    "import runpy, sys\nsys.argv = ['crankbench', '--help']\ntry:\n"
    "    runpy.run_module('crankbench', run_name='__main__')\nexcept SystemExit:\n    pass",
    # a read of a large HDF5 record scans it with numpy unless numba is already loaded
    # (measure.scan.BlockExtremes: importing numba costs more than it saves on a read)
    "import tempfile, pathlib, numpy as np\nfrom crankbench.measure import io\n"
    "from crankbench.measure.record import make_record\n"
    "p = pathlib.Path(tempfile.mkdtemp()) / 'r.h5'\n"
    "x = np.random.default_rng(0).standard_normal(400_000).astype(np.float32)\n"
    "io.write(make_record({'a': dict(data=x, sample_rate=1e4, units='m/s^2',\n"
    "                                 quantity='acceleration')}), p)\n"
    "assert io.read(p)['a'].size == x.size",
])
def test_no_heavy_optional_module_at_start_up(code):
    assert _heavy_loaded(code) == "[]"
