"""What a command reads and what it writes, so that no output ever resolves to an input.

Every command that writes collects its inputs — records with their sidecars (``run.wav`` and
``run.wav.json``), models with every file they reference (a shaft line's engine, a scene's
engine, shaft line and mounts, recursively), channel maps — and refuses, before any work, an
output that is the same file as one of them, whatever ``--overwrite`` says: same path after
resolving symbolic links, or the same inode (a hard link). Outputs of one command must also be
distinct from each other.
"""

from __future__ import annotations

import os
from pathlib import Path

from crankbench.measure._atomic import same_file

__all__ = ["record_inputs", "model_inputs", "map_inputs", "check_outputs", "sidecars_of"]

#: suffixes a record may carry beside it (``<record><suffix>``): the WAV sidecar and any
#: metadata JSON a reader may look for
_SIDECAR_SUFFIXES = (".json",)


def sidecars_of(path) -> list[Path]:
    """Files a reader or writer of ``path`` uses beside it (``run.wav.json`` for ``run.wav``)."""
    suffixes = set(_SIDECAR_SUFFIXES)
    try:
        from crankbench.measure.readers import module_for

        suffixes |= set(getattr(module_for(path), "SIDECARS", ()))
    except Exception:  # noqa: BLE001 - unknown extension: the generic sidecars only
        pass
    return [Path(str(path) + s) for s in sorted(suffixes)]


def record_inputs(path, what: str = "the record") -> list[tuple[Path, str]]:
    """A record file and its sidecars (existing or not: an output there is refused too), as
    (path, description) pairs for :func:`check_outputs`."""
    path = Path(path)
    return [(path, f"{what} {path}")] + [(p, f"the sidecar of {what} {path}")
                                          for p in sidecars_of(path)]


def model_inputs(path, what: str = "the model") -> list[tuple[Path, str]]:
    """A TOML model and every existing file its string values name (relative to the model's
    folder, recursively through referenced TOML files), as (path, description) pairs."""
    return _model_inputs(Path(path), what, set())


def map_inputs(args) -> list[tuple[Path, str]]:
    """The channel map of a command (``--map``), if any, as (path, description) pairs."""
    path = getattr(args, "map", None)
    return model_inputs(path, "the channel map") if path else []


def _model_inputs(path, what, seen):
    import tomllib

    key = os.path.realpath(path)
    if key in seen:
        return []
    seen.add(key)
    out = [(path, f"{what} {os.path.normpath(path)}")]
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return out  # the loader reports it; only the file itself is known
    for text in _strings(data):
        if len(text) > 4096 or "\n" in text or not text.strip():
            continue
        ref = path.parent / text
        try:
            if ref.is_file():
                named = f"a file named by {path.name}:"
                out.extend(_model_inputs(ref, named, seen) if ref.suffix.lower() == ".toml"
                           else [(ref, named)])
        except (OSError, ValueError):
            continue
    return out


def _strings(node):
    if isinstance(node, str):
        yield node
    elif isinstance(node, dict):
        for v in node.values():
            yield from _strings(v)
    elif isinstance(node, list):
        for v in node:
            yield from _strings(v)


def check_outputs(outputs, inputs, *, error=None) -> None:
    """Refuse outputs that are an input or each other (before any work).

    Parameters
    ----------
    outputs : iterable of (path, how)
        Each output with how the user named it (``"-o rec.csv"``, ``"--reports DIR"``).
    inputs : iterable of (path, what)
        Each input with what it is (from :func:`record_inputs`, :func:`model_inputs`).
    error : type, optional
        Exception class (default ConfigError).

    Raises
    ------
    ConfigError
        ``-o rec.csv is the record rec.csv: an output never replaces an input, whatever
        --overwrite says; choose another output name``.
    """
    from crankbench.predict.errors import ConfigError

    error = error or ConfigError
    inputs = [(Path(p), what) for p, what in inputs]
    done = []
    for out, how in outputs:
        out = Path(out)
        for src, what in inputs:
            if same_file(out, src):
                verb = "is" if os.path.abspath(out) == os.path.abspath(src) else \
                    "resolves to (is a link to)"
                raise error(f"{how} {verb} one of the inputs ({what}): an output never "
                            "replaces an input, whatever --overwrite says; choose another "
                            "output name")
        for other, other_how in done:
            if same_file(out, other):
                raise error(f"{how} and {other_how} are the same file {out}; every output "
                            "needs its own name")
        done.append((out, how))
