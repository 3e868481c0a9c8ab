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

__all__ = ["atomic_path", "atomic_paths", "atomic_dir", "check_output_dir", "ensure_output_dir"]


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


def check_output_dir(path: str | os.PathLike, *, protect: tuple = ()) -> Path:
    """Check, before any work, that folder ``path`` can be written as a whole.

    Nothing is created. The folder may exist (it will be replaced, see
    :func:`atomic_dir`) or not (its nearest existing ancestor must be a writable
    folder). Refused with :class:`InputError`: a path that is a file, under a file,
    in a folder that is not writable, the current folder or one of its ancestors, or
    a folder holding one of the ``protect`` paths (the job's own inputs).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> check_output_dir(d / "new" / "run") == d / "new" / "run"
    True
    >>> (d / "f").write_text("x") and None
    >>> check_output_dir(d / "f")
    Traceback (most recent call last):
    ...
    map2map.core.errors.InputError: ...: output path exists and is not a directory
    """
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise InputError(p, "output path exists and is not a directory")
    full = p.resolve()
    if full == Path.cwd().resolve() or full in Path.cwd().resolve().parents:
        raise InputError(p, "the output folder is replaced whole: it cannot be the "
                         "current folder or one of its parents")  # fmt: skip
    if p.is_dir():
        for q in protect:
            if q is None or not isinstance(q, str | os.PathLike):
                continue
            try:
                Path(q).resolve().relative_to(full)
            except ValueError:
                continue
            raise InputError(p, f"the output folder is replaced whole and holds the input {q}")
    anc = full.parent
    while not anc.exists():
        anc = anc.parent
    if not anc.is_dir():
        raise InputError(p, f"cannot create the output folder: {anc} is not a directory")
    if not os.access(anc, os.W_OK | os.X_OK):
        raise InputError(p, f"output folder cannot be created: {anc} is not writable")
    return p


@contextlib.contextmanager
def atomic_dir(path: str | os.PathLike, *, protect: tuple = ()) -> Iterator[Path]:
    """Yield a temporary sibling folder of ``path``; on success it becomes ``path`` whole.

    A folder of outputs exists complete or not at all: the caller writes everything
    into the yielded folder (``.NAME.tmp-XXXX`` beside ``path``); when the block ends
    without an exception it is renamed to ``path``. An exception or Ctrl-C inside the
    block removes the temporary folder (``finally``) and leaves ``path`` as it was.

    The rule for an existing ``path``: it is **replaced** as a whole, atomically
    enough that no reader ever sees a mixture: the old folder is renamed away
    (``.NAME.old-XXXX``), the new one renamed in, then the old one deleted. Old files
    that the new run does not write do not survive. :func:`check_output_dir` (called
    first) refuses the current folder, its parents and a folder holding ``protect``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_dir(d / "run") as tmp:
    ...     _ = (tmp / "a.txt").write_text("hello")
    >>> sorted(p.name for p in d.iterdir()), (d / "run" / "a.txt").read_text()
    (['run'], 'hello')
    >>> try:
    ...     with atomic_dir(d / "run2") as tmp:
    ...         _ = (tmp / "half.txt").write_text("...")
    ...         raise RuntimeError("interrupted")
    ... except RuntimeError:
    ...     pass
    >>> sorted(p.name for p in d.iterdir())
    ['run']
    """
    import shutil

    final = check_output_dir(path, protect=protect)
    parent = final.parent if str(final.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}.tmp-", dir=parent))
    except OSError as exc:
        raise InputError(final, f"output folder cannot be created ({exc.strerror})") from None
    old: Path | None = None
    try:
        yield tmp
        os.chmod(tmp, 0o755 & ~_umask())
        if final.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{final.name}.old-", dir=parent))
            os.replace(final, old / final.name)
        os.replace(tmp, final)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
        if old is not None:
            if not final.exists() and (old / final.name).exists():  # put the old one back
                with contextlib.suppress(OSError):
                    os.replace(old / final.name, final)
            shutil.rmtree(old, ignore_errors=True)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
