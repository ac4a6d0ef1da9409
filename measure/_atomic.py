"""Atomic output: write to a temporary file beside the target, then rename over it.

A crash mid-write leaves either the old file or no file, never a truncated one; an existing
output is never replaced unless the caller says ``overwrite=True``.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

__all__ = ["atomic_path", "check_overwrite", "same_file"]


def same_file(a: str | Path, b: str | Path) -> bool:
    """True when paths ``a`` and ``b`` name the same file: equal after resolving symbolic
    links and ``..``, or the same inode (a hard link). Either may not exist yet.

    Examples
    --------
    >>> import os, tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "rec.csv").write_text("x")
    >>> os.link(d / "rec.csv", d / "copy.csv"); os.symlink(d / "rec.csv", d / "link.csv")
    >>> same_file(d / "copy.csv", d / "rec.csv"), same_file(d / "link.csv", d / "rec.csv")
    (True, True)
    >>> same_file(d / "sub" / ".." / "rec.csv", d / "rec.csv"), same_file(d / "new.csv", d / "rec.csv")
    (True, False)
    """
    try:
        if os.path.samefile(a, b):
            return True
    except OSError:  # one of them does not exist (yet)
        pass
    return os.path.realpath(os.path.abspath(a)) == os.path.realpath(os.path.abspath(b))


def check_overwrite(path: str | Path, overwrite: bool, *, option: str = "overwrite=True") -> Path:
    """Raise ``FileExistsError`` naming ``option`` if ``path`` exists and ``overwrite`` is False."""
    path = Path(path)
    if path.exists() and not path.is_file() and not path.is_dir():
        # a device, pipe or socket (/dev/null): renaming over it would replace the node itself
        raise FileExistsError(f"{path} is not a regular file (a device, pipe or socket); "
                              "choose a file path")
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
