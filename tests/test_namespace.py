"""One installed namespace: the wheel installs ``crankbench`` and nothing else at the top level,
and works next to unrelated distributions that own the names ``analysis``, ``measure`` and
``predict`` (issue 22)."""

import json
import os
import shutil
import subprocess
import sys
import tomllib
import venv
import zipfile
from pathlib import Path

import pytest

import crankbench

ROOT = Path(__file__).resolve().parents[1]
SUBPACKAGES = ("analysis", "measure", "predict")


def _clean_env():
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["MPLBACKEND"] = "Agg"
    return env


def test_pyproject_lists_every_package():
    """``[tool.setuptools] packages`` names every folder with an ``__init__.py`` (a missing one
    would be left out of the wheel while the editable install still finds it)."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    on_disk = {"crankbench"}
    for sub in SUBPACKAGES:
        for init in (ROOT / sub).rglob("__init__.py"):
            parts = init.parent.relative_to(ROOT).parts
            on_disk.add(".".join(("crankbench", *parts)))
    assert set(config["packages"]) == on_disk | {"crankbench.sample_data"}
    assert config["package-dir"] == {"crankbench": "crankbench",
                                     "crankbench.sample_data": "sample_data",
                                     **{f"crankbench.{s}": s for s in SUBPACKAGES}}


def test_version_and_subpackages():
    from importlib.metadata import version

    assert crankbench.__version__ == version("crankbench")  # the one version, read by the build
    assert {"analysis", "measure", "predict"} <= set(dir(crankbench))
    assert crankbench.predict.__name__ == "crankbench.predict"
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        crankbench.nothing  # noqa: B018


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    out = tmp_path_factory.mktemp("wheel")
    source = tmp_path_factory.mktemp("source")  # build from a copy: nothing written into the clone
    for name in ("crankbench", "sample_data", *SUBPACKAGES):
        shutil.copytree(ROOT / name, source / name, ignore=shutil.ignore_patterns("__pycache__"))
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy2(ROOT / name, source / name)
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                           "-q", "-w", str(out), str(source)], capture_output=True, text=True,
                          env=_clean_env(), timeout=600)
    assert done.returncode == 0, done.stderr
    (path,) = out.glob("crankbench-*.whl")
    return path


def test_wheel_installs_one_top_level_package(wheel):
    with zipfile.ZipFile(wheel) as z:
        names = z.namelist()
    tops = {name.split("/")[0] for name in names}
    assert tops == {"crankbench", f"crankbench-{crankbench.__version__}.dist-info"}
    for sub in SUBPACKAGES:
        assert f"crankbench/{sub}/__init__.py" in names
    assert any(n.startswith("crankbench/analysis/report/templates/") for n in names)
    assert "crankbench/sample_data/scenes/marine_6l_runup.toml" in names
    assert not [n for n in names if n.endswith((".h5", ".mf4", ".csv", ".wav"))]
    with zipfile.ZipFile(wheel) as z:
        entry = z.read(f"crankbench-{crankbench.__version__}.dist-info/entry_points.txt").decode()
    assert "crankbench = crankbench.analysis.cli:main" in entry


def _make_standins(where: Path) -> Path:
    """A tiny unrelated distribution owning the top-level names analysis, measure, predict."""
    project = where / "standins"
    for name in SUBPACKAGES:
        (project / name).mkdir(parents=True)
        (project / name / "__init__.py").write_text(f"OWNER = 'standins-{name}'\n")
    (project / "pyproject.toml").write_text(
        '[build-system]\nrequires = ["setuptools"]\nbuild-backend = "setuptools.build_meta"\n'
        '[project]\nname = "standins"\nversion = "1.0"\n'
        '[tool.setuptools]\npackages = ["analysis", "measure", "predict"]\n')
    return project


def test_wheel_runs_the_demo_next_to_packages_owning_the_bare_names(wheel, tmp_path):
    env_dir = tmp_path / "venv"
    # dependencies come from this interpreter's site-packages; the wheel and the stand-ins are
    # installed into the new environment itself, which comes first on its sys.path
    venv.EnvBuilder(system_site_packages=True, with_pip=False).create(env_dir)
    python = env_dir / "bin" / "python"
    env = _clean_env()
    pip = [str(python), "-m", "pip", "install", "-q", "--no-deps", "--no-build-isolation"]
    for target in (str(wheel), str(_make_standins(tmp_path))):
        done = subprocess.run(pip + [target], capture_output=True, text=True, env=env,
                              cwd=tmp_path, timeout=600)
        assert done.returncode == 0, done.stderr

    probe = ("import json, crankbench, crankbench.analysis.cli, analysis, measure, predict;"
             "print(json.dumps({'crankbench': crankbench.__file__, "
             "'cli': crankbench.analysis.cli.__file__, "
             "'owners': [analysis.OWNER, measure.OWNER, predict.OWNER]}))")
    done = subprocess.run([str(python), "-c", probe], capture_output=True, text=True, env=env,
                          cwd=tmp_path, timeout=300)
    assert done.returncode == 0, done.stderr
    found = json.loads(done.stdout)
    assert Path(found["crankbench"]).is_relative_to(env_dir)
    assert Path(found["cli"]).is_relative_to(env_dir / "lib")
    assert found["owners"] == ["standins-analysis", "standins-measure", "standins-predict"]

    script = env_dir / "bin" / "crankbench"
    done = subprocess.run([str(script), "demo", "-q", "-o", str(tmp_path / "demo"), "--json"],
                          capture_output=True, text=True, env=env, cwd=tmp_path, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    assert (tmp_path / "demo" / "report.html").stat().st_size > 10_000
