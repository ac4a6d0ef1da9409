"""Property-based tests of the model loaders on random TOML documents.

Valid engine, shaft-line, rotor and scene models (bases in ``tests/corpus/make_bad_models.py``)
are mutated by hypothesis — keys set to random values of any TOML type (negative, zero, NaN,
inf, huge, strings, booleans, arrays, tables), deleted, or misspelt — written as TOML and
loaded. Each load gives a :class:`~predict.errors.ModelError` (a scene: ``ConfigError``, or
``FileNotFoundError`` for a model path that does not resolve) naming the file, or a model whose
derived numbers are finite; never another exception.
"""

from __future__ import annotations

import importlib.util
import json
import math
import re
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from crankbench.predict.errors import ConfigError, CrankbenchError, ModelError

CORPUS = Path(__file__).resolve().parents[1] / "corpus"
FUZZ = settings(max_examples=30, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])


def _load_generator():
    name = "crankbench_corpus_make_bad_models"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, CORPUS / "make_bad_models.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


gen = _load_generator()
ROOT = Path(__file__).resolve().parents[2]
BASES = {"engine": tomllib.loads(gen.ENGINE), "shaftline": tomllib.loads(gen.SHAFTLINE),
         "rotor": tomllib.loads(gen.ROTOR),
         "scene": tomllib.loads(gen.SCENE.replace("../../../../sample_data",
                                                  str(ROOT / "sample_data")))}


# ------------------------------------------------------------------------------ TOML writing
def _key(k: str) -> str:
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)


def toml_value(v) -> str:
    """Inline TOML for a scalar, array or table (written by hand: no extra dependency)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(type(v))


def toml_document(doc: dict) -> str:
    """Top-level tables as ``[name]`` sections with inline values; other keys first."""
    head = [f"{_key(k)} = {toml_value(v)}" for k, v in doc.items() if not isinstance(v, dict)]
    body = []
    for k, v in doc.items():
        if isinstance(v, dict):
            body.append(f"[{_key(k)}]")
            body += [f"{_key(kk)} = {toml_value(vv)}" for kk, vv in v.items()]
    return "\n".join(head + body) + "\n"


def test_toml_writer_round_trips_the_bases():
    for base in BASES.values():
        assert tomllib.loads(toml_document(base)) == base


# ------------------------------------------------------------------------------ mutations
scalars = st.one_of(
    st.integers(-10, 10), st.integers(-2**63, 2**63 - 1),
    st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([0.0, -0.0, 1e-300, 1e300]),
    st.text(max_size=8), st.booleans())
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=6), st.dictionaries(st.sampled_from(["a", "name", "inertia",
                                                                  "from", "to"]), inner,
                                                 max_size=3)), max_leaves=8)


def _tables(doc):
    """Every mutable table in the document: (container, key path) pairs."""
    out = []

    def walk(t, path):
        out.append((t, path))
        for k, v in t.items():
            if isinstance(v, dict):
                walk(v, path + [k])
            elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
                for i, x in enumerate(v):
                    walk(x, path + [f"{k}[{i}]"])

    walk(doc, [])
    return out


@st.composite
def mutated(draw, kind):
    doc = json.loads(json.dumps(BASES[kind]))        # deep copy
    tables = _tables(doc)
    for _ in range(draw(st.integers(1, 4))):
        table, _path = draw(st.sampled_from(tables))
        keys = list(table)
        op = draw(st.sampled_from(["set", "set", "delete", "typo", "new"]))
        if op in ("set", "delete", "typo") and not keys:
            op = "new"
        if op == "set":
            table[draw(st.sampled_from(keys))] = draw(values)
        elif op == "delete":
            table.pop(draw(st.sampled_from(keys)))
        elif op == "typo":
            k = draw(st.sampled_from(keys))
            v = table.pop(k)
            i = draw(st.integers(0, max(0, len(k) - 1)))
            table[k[:i] + k[i + 1:] or "x"] = v
        else:
            table[draw(st.text("abcdefghijklmnopqrstuvwxyz_", min_size=1, max_size=10))] = \
                draw(values)
    return doc


def _load(kind, path):
    if kind == "engine":
        from crankbench.predict.engine import Engine

        return Engine.from_toml(path)
    if kind == "shaftline":
        from crankbench.predict.torsion import from_toml

        return from_toml(path)
    if kind == "scene":
        from crankbench.measure.synth.scene import Scene

        return Scene.from_toml(path)
    from crankbench.predict.lateral import load_rotor

    return load_rotor(path)


def _check_model(kind, model):
    if kind == "engine":
        assert model.n_cylinders >= 1
        assert 0 < model.lam < 1
        assert np.all(np.isfinite(model.firing_angles_deg()))
        x = model.piston_motion(np.linspace(0, 4 * np.pi, 7))
        for part in (x if isinstance(x, tuple) else (x,)):
            assert np.all(np.isfinite(np.asarray(part, dtype=float)))
    elif kind == "shaftline":
        f = model.natural_frequencies()
        assert np.all(np.isfinite(f)) and np.all(f >= 0)


def _roundtrip(kind, doc, tmp_path):
    path = tmp_path / f"fuzzed_{kind}.toml"
    path.write_text(toml_document(doc), encoding="utf-8")
    try:
        model = _load(kind, path)
    except ModelError as exc:
        assert path.name in str(exc), f"message does not name the file: {exc}"
        return None
    except (ConfigError, FileNotFoundError) as exc:
        # scenes: their own keys are ConfigErrors; a model path that does not resolve is a
        # FileNotFoundError; both name the scene file
        assert kind == "scene", f"{type(exc).__name__} from the {kind} loader: {exc}"
        assert path.name in str(exc), f"message does not name the file: {exc}"
        return None
    except CrankbenchError as exc:  # pragma: no cover - would be a wrong family for a model
        raise AssertionError(f"{type(exc).__name__} instead of ModelError: {exc}") from None
    _check_model(kind, model)
    return model


@pytest.mark.parametrize("kind", ["engine", "shaftline", "rotor", "scene"])
@FUZZ
@given(data=st.data())
def test_mutated_model_gives_model_error_or_valid_model(kind, data, tmp_path):
    _roundtrip(kind, data.draw(mutated(kind)), tmp_path)


@FUZZ
@given(doc=st.dictionaries(st.sampled_from(["engine", "shaftline", "rotor", "limits", "x"]),
                           st.dictionaries(st.text(max_size=6), values, max_size=4),
                           max_size=3))
def test_random_documents_give_model_error(doc, tmp_path):
    """Documents with random tables: never a valid engine by accident, always our error."""
    for kind in ("engine", "shaftline", "rotor"):
        _roundtrip(kind, doc, tmp_path)
