"""Memory budgets of the commands: refuse a map too large *before* the heavy work.

Issue 11, item 4: a 12000 x 12000 px map ran ``evaluate`` into 23.4 GB and an OpenCV
traceback, and got ``simulate`` killed for memory. Every command that reads a map
now has a measured memory model (:data:`MODELS`, fitted by
``benchmarks/bench_memory.py``; the table is in ``docs/memory.md``)::

    peak RSS  ~=  base + bytes_per_pixel * pixels

and a budget (:data:`DEFAULT_BUDGET_BYTES`, 4 GiB). A map whose estimate exceeds
the budget is refused with one line naming the file, its size, the estimate and the
way out (downsample with ``map2map prep --size``, or ``--max-pixels`` to try anyway)
before it is decoded: the map readers call :func:`check_map_size` with the size read
from the file's header (PGM/PNG) or computed from a drawing's extent (HouseExpo
JSON, DXF) before they allocate the grid.

Which command is running is set once by the command line (:func:`for_command`, a
context manager around the command), so the readers deep inside ``maps`` need no
extra parameter; library callers may use it too. Outside any command only
:data:`READ_MAX_PIXELS` applies (what any reader refuses to decode at all).

Examples
--------
>>> from map2map.core.limits import check_map_size, for_command, max_pixels
>>> max_pixels("evaluate") > 4_000_000
True
>>> with for_command("evaluate"):
...     try:
...         check_map_size((20000, 20000), "big.pgm")
...     except Exception as exc:
...         print(str(exc)[:52])
big.pgm: 20000 x 20000 px (400.0 MP): evaluate would
>>> with for_command("evaluate", max_pixels=0):  # 0: no limit
...     check_map_size((20000, 20000), "big.pgm")
"""

from __future__ import annotations

import contextlib
import contextvars
import math
import os
from collections.abc import Iterator
from dataclasses import dataclass

from .errors import InputError

__all__ = [
    "DEFAULT_BUDGET_BYTES",
    "READ_MAX_PIXELS",
    "MemoryModel",
    "MODELS",
    "estimate_bytes",
    "max_pixels",
    "check_map_size",
    "for_command",
    "active_command",
]

#: Peak resident memory a command may plan for (bytes): 4 GiB, a laptop's share.
DEFAULT_BUDGET_BYTES = 4 * 2**30

#: No reader decodes more pixels than this, whatever the command (OpenCV's own cap
#: is 2**30; a 50000 x 50000 header is refused before any allocation).
READ_MAX_PIXELS = 2**30


@dataclass(frozen=True)
class MemoryModel:
    """Peak RSS of one command as a line in the map's pixel count.

    Parameters
    ----------
    base_mb : float
        Interpreter, imports and fixed-size work (MiB).
    bytes_per_pixel : float
        Slope in bytes per pixel of the largest input map.

    Examples
    --------
    >>> MemoryModel(100, 10).estimate(2**20) / 2**20
    110.0
    """

    base_mb: float
    bytes_per_pixel: float

    def estimate(self, pixels: int) -> float:
        """Estimated peak RSS in bytes for a map of ``pixels`` pixels."""
        return self.base_mb * 2**20 + self.bytes_per_pixel * float(pixels)


#: Measured models (``benchmarks/bench_memory.py``: least-squares fit of the peak
#: RSS over 0.25-16 MP, slopes rounded up ~10 %, bases to 20 MB; ``docs/memory.md``
#: has the raw table). ``align`` shares ``evaluate``'s model (the same alignment);
#: ``simulate``'s is its default 7-minute exploration, ``slam``'s was per pixel of the
#: dense grids' extent with 30 particles: it now bounds only a map a ``slam`` run reads
#: (a simulator run's plan); the run itself is checked against its own memory estimate
#: (:func:`map2map.slam.offline.memory_estimate`, ``--max-memory``).
MODELS: dict[str, MemoryModel] = {
    "convert": MemoryModel(60, 6),
    "prep": MemoryModel(60, 9),
    "show": MemoryModel(300, 4),
    "align": MemoryModel(240, 236),
    "evaluate": MemoryModel(240, 236),
    "deform": MemoryModel(400, 195),
    "simulate": MemoryModel(240, 240),
    "slam": MemoryModel(300, 400),
}


@dataclass(frozen=True)
class _Active:
    command: str
    max_pixels: int | None  # None: from the budget; 0: no limit


_ACTIVE: contextvars.ContextVar[_Active | None] = contextvars.ContextVar(
    "map2map_active_command", default=None
)


@contextlib.contextmanager
def for_command(command: str, max_pixels: int | None = None) -> Iterator[None]:
    """Make ``command``'s budget the one map readers check inside the block.

    Parameters
    ----------
    command : str
        A key of :data:`MODELS` (another name only gets :data:`READ_MAX_PIXELS`).
    max_pixels : int, optional
        Override: the largest map (pixels) to accept; ``0`` accepts any size up to
        :data:`READ_MAX_PIXELS` (the command line's ``--max-pixels``).

    Examples
    --------
    >>> with for_command("deform", max_pixels=10):
    ...     active_command()
    'deform'
    """
    if max_pixels is not None and max_pixels < 0:
        raise InputError("max_pixels", f"must be >= 0 (0: no limit), got {max_pixels}")
    token = _ACTIVE.set(_Active(command, max_pixels))
    try:
        yield
    finally:
        _ACTIVE.reset(token)


def active_command() -> str | None:
    """The command set by the innermost :func:`for_command`, else None."""
    a = _ACTIVE.get()
    return None if a is None else a.command


def estimate_bytes(command: str, pixels: int) -> float:
    """Estimated peak RSS (bytes) of ``command`` on a map of ``pixels`` pixels.

    >>> estimate_bytes("convert", 0) == MODELS["convert"].base_mb * 2**20
    True
    """
    return MODELS[command].estimate(pixels)


def max_pixels(command: str, budget_bytes: float = DEFAULT_BUDGET_BYTES) -> int:
    """The largest map (pixels) ``command`` accepts within ``budget_bytes``.

    >>> max_pixels("convert", 2**30) > max_pixels("evaluate", 2**30)
    True
    """
    m = MODELS.get(command)
    if m is None:
        return READ_MAX_PIXELS
    room = budget_bytes - m.base_mb * 2**20
    return int(min(READ_MAX_PIXELS, max(0.0, room / m.bytes_per_pixel)))


def _gb(b: float) -> str:
    return f"{b / 2**30:.1f} GB"


def check_map_size(
    shape: tuple[int, int], source, command: str | None = None, *, way_out: str | None = None
) -> None:
    """Refuse a map of ``shape`` (rows, columns) too large for the running command.

    Call it before allocating anything of the map's size (readers call it with
    the size from the file's header).

    Parameters
    ----------
    shape : (int, int)
        Rows and columns the map has or would have.
    source : path-like or str
        The file, named in the message.
    command : str, optional
        Defaults to the one set by :func:`for_command`.
    way_out : str, optional
        What the user can do instead (default: downsample with ``map2map prep``).

    Raises
    ------
    InputError
        One line: the file, its size, the command's estimated memory and budget,
        and the way out (``map2map prep IN OUT --size N`` or ``max_pixels``).
    """
    h, w = int(shape[0]), int(shape[1])
    pixels = h * w
    active = _ACTIVE.get()
    if command is None and active is not None:
        command = active.command
    override = active.max_pixels if active is not None and active.command == command else None
    size = f"{h} x {w} px ({pixels / 1e6:.1f} MP)"
    if pixels > READ_MAX_PIXELS:
        raise InputError(
            source,
            f"{size}: over the {READ_MAX_PIXELS / 1e6:.0f} MP any reader accepts; "
            f"{way_out or 'downsample it first (a coarser resolution)'}",
        )
    if override == 0:
        return
    if override is not None:
        limit = override
    elif command is not None and command in MODELS:
        limit = max_pixels(command)
    else:
        return
    if pixels <= limit:
        return
    side = max(1, math.isqrt(limit))
    if way_out is None:
        way_out = f"downsample it (map2map prep {os.fspath(source)} SMALL.png --size {side})"
    if command in MODELS:
        need = f"{command} would need about {_gb(estimate_bytes(command, pixels))}, "
        budget = (
            f"over the `max_pixels={limit}` given"
            if override is not None
            else f"over its {_gb(DEFAULT_BUDGET_BYTES)} budget (up to {limit / 1e6:.1f} MP)"
        )
    else:
        need, budget = "", f"over the `max_pixels={limit}` given"
    raise InputError(
        source,
        f"{size}: {need}{budget}; {way_out} or pass `max_pixels={pixels}` to try anyway",
    )
