"""Atomic output: write to a temporary file beside the target, then rename over it.

A crash mid-write leaves either the old file or no file, never a truncated one; an existing
output is never replaced unless the caller says ``overwrite=True``.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

__all__ = ["atomic_path", "check_overwrite"]


def check_overwrite(path: str | Path, overwrite: bool, *, option: str = "overwrite=True") -> Path:
    """Raise ``FileExistsError`` naming ``option`` if ``path`` exists and ``overwrite`` is False."""
    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass {option} to replace it")
    if path.is_dir():
        raise IsADirectoryError(f"{path} is a directory, expected a file path")
    return path


@contextlib.contextmanager
def atomic_path(path: str | Path, *, overwrite: bool = False, option: str = "overwrite=True"):
    """Yield a temporary path in the target's directory; on success rename it to ``path``.

    Parameters
    ----------
    path : path-like
        Final output path.
    overwrite : bool
        Replace an existing file. If False and ``path`` exists, ``FileExistsError`` is raised
        before anything is written.
    option : str
        How the caller spells "overwrite" in its interface (``--overwrite`` for the CLI).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "out.txt"
    >>> with atomic_path(target) as tmp:
    ...     _ = tmp.write_text("data")
    >>> target.read_text()
    'data'
    """
    path = check_overwrite(path, overwrite, option=option)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp)
    # mkstemp creates 0600; give the output the permissions an ordinary open() would
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    try:
        yield tmp
        if not overwrite and path.exists():
            raise FileExistsError(f"{path} appeared while writing; pass {option} to replace it")
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
