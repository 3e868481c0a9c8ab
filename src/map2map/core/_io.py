"""Atomic output: write to a temporary name in the same folder, then rename.

Nothing half-written is ever left under the final name: if writing fails, the
temporary file is removed and the old file (if any) is untouched.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from .errors import InputError

__all__ = ["atomic_path", "atomic_paths", "ensure_output_dir"]


def ensure_output_dir(path: str | os.PathLike, *, is_dir: bool = True) -> Path:
    """Create (if needed) the folder that will hold outputs, and check it is writable.

    ``path`` is the output folder itself (``is_dir=True``) or a file whose parent
    folder must be writable. Raises :class:`InputError` naming the folder otherwise.

    Parameters
    ----------
    path : path-like
        The output folder (``is_dir=True``) or an output file.
    is_dir : bool
        Whether ``path`` is the folder itself or a file in it.

    Returns
    -------
    pathlib.Path
        ``path`` as a Path; its folder now exists and is writable.

    Raises
    ------
    InputError
        The folder cannot be created or is not writable; ``path`` is a file where a
        folder is expected.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = ensure_output_dir(pathlib.Path(tempfile.mkdtemp()) / "run" / "maps")
    >>> out.is_dir(), out.name
    (True, 'maps')
    """
    p = Path(path)
    folder = p if is_dir else (p.parent if str(p.parent) else Path("."))
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(folder, f"output directory cannot be created ({exc.strerror})") from None
    if not folder.is_dir():
        raise InputError(folder, "output path exists and is not a directory")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InputError(folder, "output directory is not writable")
    return p


@contextlib.contextmanager
def atomic_paths(*paths: str | os.PathLike) -> Iterator[list[Path]]:
    """Yield temporary paths beside each target; rename them all into place on success.

    Parameters
    ----------
    *paths : path-like
        The files to write; missing folders are created.

    Yields
    ------
    list of pathlib.Path
        One temporary path per target, in the same order; nothing is renamed (and
        the temporary files are removed) when the block raises.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_paths(d / "a.txt") as (tmp,):
    ...     _ = tmp.write_text("hello")
    >>> (d / "a.txt").read_text()
    'hello'
    """
    targets = [Path(p) for p in paths]
    for t in targets:
        ensure_output_dir(t, is_dir=False)
    temps: list[Path] = []
    try:
        for t in targets:
            fd, name = tempfile.mkstemp(
                prefix=f".{t.name}.", suffix=".tmp" + t.suffix, dir=t.parent
            )
            os.close(fd)
            temps.append(Path(name))
        yield temps
        for tmp, t in zip(temps, targets, strict=True):
            os.chmod(tmp, 0o644)
            os.replace(tmp, t)
        temps = []
    finally:
        for tmp in temps:
            with contextlib.suppress(OSError):
                tmp.unlink()


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Single-file form of :func:`atomic_paths`.

    Parameters
    ----------
    path : path-like
        The file to write.

    Yields
    ------
    pathlib.Path
        A temporary path beside ``path``, renamed onto it when the block ends without error.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "b.txt"
    >>> with atomic_path(target) as tmp:
    ...     _ = tmp.write_text("x")
    >>> target.read_text()
    'x'
    """
    with atomic_paths(path) as (tmp,):
        yield tmp
