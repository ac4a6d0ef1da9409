"""The public API follows the speed, angle and plot conventions of docs/DESIGN.md (issue 22):
parameter names say their unit, renamed keywords survive one release as deprecated aliases,
functions of time return labelled arrays, and ``plot(ax=None)`` returns the Figure."""

import ast
import dataclasses
import importlib
import inspect
import pkgutil
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]

#: parameters with "speed" in the name that carry no speed unit, and why
DIMENSIONLESS = {
    "speed_tolerance": "relative: a fraction of the mean speed",
}
FORBIDDEN = {"rpm", "speed", "speeds", "max_speed", "speed2", "rpm_bins", "n_rpm", "rev_per_min"}


def _public_modules():
    names = []
    for sub in ("predict", "measure", "analysis"):
        package = importlib.import_module(f"crankbench.{sub}")
        names.append(package.__name__)
        names += [i.name for i in pkgutil.walk_packages(package.__path__, package.__name__ + ".")]
    return [n for n in names if not any(p.startswith("_") for p in n.split(".")[1:])
            and ".commands" not in n and ".bench" not in n]


def _public_callables():
    """(qualified name, function) of every public function and public method."""
    out = []
    for name in _public_modules():
        module = importlib.import_module(name)
        exported = getattr(module, "__all__", None) or [
            n for n, o in vars(module).items()
            if not n.startswith("_") and getattr(o, "__module__", None) == name]
        for export in exported:
            obj = getattr(module, export, None)
            if inspect.isfunction(obj):
                out.append((f"{name}.{export}", obj))
            elif inspect.isclass(obj) and obj.__module__ == name:
                for attr, value in vars(obj).items():
                    if attr.startswith("_") and attr != "__init__":
                        continue
                    if attr == "__init__" and dataclasses.is_dataclass(obj):
                        continue  # result records: fields are attributes, built internally
                    func = getattr(value, "__func__", value)
                    if inspect.isfunction(func):
                        out.append((f"{name}.{export}.{attr}", func))
    return out


CALLABLES = _public_callables()


def _unit_ok(param: str) -> bool:
    if param in FORBIDDEN:
        return False
    if "rpm" in param and not param.endswith("_rpm"):
        return False
    if "speed" in param:
        return (param.endswith("_rpm") or param.endswith("_channel") or param.startswith("n_")
                or param in DIMENSIONLESS)
    return True


def test_the_walk_sees_the_api():
    names = {q for q, _ in CALLABLES}
    assert len(names) > 300
    for expected in ("crankbench.analysis.orders.order_track",
                     "crankbench.predict.torsion.system.TorsionalSystem.critical_speeds",
                     "crankbench.measure.io.read"):
        assert expected in names


def test_speed_parameters_say_their_unit():
    bad = [f"{q}({p})" for q, f in CALLABLES for p in inspect.signature(f).parameters
           if not _unit_ok(p)]
    assert bad == []


def test_the_rule_catches_what_it_should():
    assert not _unit_ok("rpm") and not _unit_ok("speed") and not _unit_ok("rpm_bins")
    assert not _unit_ok("max_speed") and not _unit_ok("speed_limit")
    assert _unit_ok("speed_rpm") and _unit_ok("speed_range_rpm") and _unit_ok("omega")
    assert _unit_ok("speed_channel") and _unit_ok("n_speeds")


def test_every_deprecated_alias_points_at_a_real_parameter():
    aliased = [(q, f) for q, f in CALLABLES if hasattr(f, "__renamed_kwargs__")]
    assert len(aliased) >= 15
    for q, f in aliased:
        params = inspect.signature(f).parameters
        for old, new in f.__renamed_kwargs__.items():
            assert new in params, f"{q}: alias {old} -> {new} but no parameter {new}"
            assert old not in params, f"{q}: {old} is still a parameter"


def test_old_keyword_still_works_with_a_future_warning():
    from crankbench.analysis.orders import order_track
    from crankbench.analysis.resample import shaft_angle
    from crankbench.predict.rotor_balance import permissible_unbalance

    fs = 2000.0
    rpm = np.full(4000, 1800.0)
    x = 1.5 * np.cos(2 * shaft_angle(rpm, fs))
    new = order_track(x, fs=fs, speed_rpm=rpm, orders=[2], revolutions=8)
    with pytest.warns(FutureWarning, match=r"order_track\(rpm=...\) is deprecated .* speed_rpm="):
        old = order_track(x, fs=fs, rpm=rpm, orders=[2], revolutions=8)
    xr.testing.assert_identical(new, old)
    with pytest.warns(FutureWarning, match="use max_omega="):
        u_old = permissible_unbalance(6.3, rotor_mass=100.0, max_speed=314.159)
    # U_per = G m / Omega (ISO 21940-11): 6.3e-3 m/s * 100 kg / 314.159 rad/s
    assert u_old == pytest.approx(6.3e-3 * 100.0 / 314.159, rel=1e-12)
    with pytest.raises(TypeError, match="got both rpm= .* and speed_rpm="):
        order_track(x, fs=fs, rpm=rpm, speed_rpm=rpm, orders=[2])


def test_speed_reference_is_labelled():
    from crankbench.analysis.speedref import speed_reference

    t = np.arange(50) / 100.0
    rec = xr.Dataset(
        {"acc": ("time", np.zeros(50), {"units": "m/s^2", "sample_rate": 100.0}),
         "n": ("time", np.full(50, 2 * np.pi * 20.0), {"quantity": "rotational_speed",
                                                       "units": "rad/s"})},
        coords={"time": t})
    speed = speed_reference(rec, "acc")
    assert isinstance(speed, xr.DataArray)
    assert speed.dims == ("time",) and speed.attrs["units"] == "rpm"
    np.testing.assert_array_equal(speed["time"].values, t)
    np.testing.assert_allclose(speed.values, 1200.0, rtol=1e-14)


def _plot_functions():
    """Every ``plot``/``plot_*`` function or method defined in the three packages (AST)."""
    found = []
    for sub in ("predict", "measure", "analysis"):
        for path in (ROOT / sub).rglob("*.py"):
            if "bench" in path.parts or "commands" in path.parts:
                continue
            tree = ast.parse(path.read_text())
            for node in ast.walk(tree):
                if isinstance(node, ast.FunctionDef) and (node.name == "plot"
                                                          or node.name.startswith("plot_")):
                    found.append((f"{path.relative_to(ROOT)}:{node.lineno} {node.name}", node))
    return found


def test_plot_takes_ax_none_and_never_returns_the_axes():
    plots = _plot_functions()
    assert len(plots) >= 30
    for where, node in plots:
        args = node.args.args + node.args.kwonlyargs
        names = [a.arg for a in args]
        assert "ax" in names, f"{where}: no ax parameter"
        defaults = dict(zip([a.arg for a in node.args.args][::-1], node.args.defaults[::-1]))
        defaults.update({a.arg: d for a, d in zip(node.args.kwonlyargs, node.args.kw_defaults)})
        default = defaults.get("ax")
        assert isinstance(default, ast.Constant) and default.value is None, \
            f"{where}: ax must default to None"
        for ret in ast.walk(node):
            if isinstance(ret, ast.Return) and isinstance(ret.value, ast.Name):
                assert ret.value.id != "ax", f"{where}: returns the Axes, not the Figure"
        assert not any(isinstance(c, ast.Attribute) and c.attr == "show"
                       for c in ast.walk(node)), f"{where}: calls show()"


def test_plot_returns_the_figure_of_the_given_axes():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crankbench.analysis.harmonic import harmonics
    from crankbench.predict.engine import Engine
    from crankbench.predict.torsion import chain

    fig, ax = plt.subplots()
    engine = Engine.from_toml(ROOT / "sample_data/engines/i4.toml")
    theta = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    objects = [engine, chain([1.0, 2.0, 1.0], [1e4, 1e4]).mode_shapes(),
               harmonics(np.cos(theta) + 0.2 * np.sin(3 * theta), 24)]
    for obj in objects:
        assert obj.plot(ax=ax) is fig
        made = obj.plot()
        assert isinstance(made, matplotlib.figure.Figure) and made is not fig
