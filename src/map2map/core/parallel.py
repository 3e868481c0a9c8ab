"""Per-item work on the CPU's cores in worker processes, results in order.

Work that holds Python's GIL (many small numpy steps: the plan drawer,
:mod:`map2map.maps.vectorize`) gets nothing from threads. :func:`process_map` runs it in
joblib's reusable pool of worker processes (loky): started once (a fraction of a second)
and kept for later batches; workers are fresh interpreters, never forked from a parent
that may hold torch's, OpenMP's or OpenCV's threads, and the caller's ``__main__`` is not
run again in them (a script needs no ``if __name__ == "__main__"`` guard). Each worker
draws with one OpenCV thread, so that two processes do not fight over two cores.

The results are those of ``[fn(x) for x in items]``, in order, whatever ``workers`` is,
as long as ``fn`` is deterministic. Warnings ``fn`` raises in a worker are raised again
in the caller, in item order. Few items (``min_items``) or one worker run in the caller
(no pool); if a worker dies, the call runs again in the caller with a warning that says
so.

Examples
--------
>>> process_map(abs, [-1, 2, -3], workers=1)
[1, 2, 3]
>>> process_map(abs, range(-40, 0), workers=2, min_items=8)[:3]
[40, 39, 38]
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Iterable
from typing import Any

__all__ = ["process_map", "default_workers"]

#: At most this many worker processes by default.
MAX_WORKERS = 8

_one_cv_thread = False


def default_workers() -> int:
    """One worker per CPU core this process may use, at most :data:`MAX_WORKERS`.

    >>> 1 <= default_workers() <= MAX_WORKERS
    True
    """
    try:
        n = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):     # not on Linux
        n = os.cpu_count() or 1
    return max(1, min(MAX_WORKERS, n))


def _call(fn: Callable[[Any], Any], x: Any) -> tuple[Any, list[tuple]]:
    """``fn(x)`` in a worker (one OpenCV thread), with the warnings it raised."""
    global _one_cv_thread
    if not _one_cv_thread:
        import cv2

        cv2.setNumThreads(1)
        _one_cv_thread = True
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn(x)
    return out, [(w.message, w.category) for w in caught]


def process_map(fn: Callable[[Any], Any], items: Iterable[Any], *,
                workers: int | None = None, min_items: int = 16) -> list[Any]:
    """``[fn(x) for x in items]``, on ``workers`` processes when there are at least
    ``min_items`` items (module docstring).

    Parameters
    ----------
    fn : callable
        A function of an importable module; ``fn(x)`` and its result must pickle.
    items : iterable
        The inputs.
    workers : int, optional
        Worker processes (default :func:`default_workers`); 1 runs in the caller.
    min_items : int
        Fewer items than this run in the caller: the pool's start (a fraction of a
        second, once per process) costs more than it saves.

    Returns
    -------
    list
        One result per item, in order.
    """
    items = list(items)
    n = default_workers() if workers is None else max(1, int(workers))
    n = min(n, len(items))
    if n <= 1 or len(items) < max(2, min_items):
        return [fn(x) for x in items]
    from joblib import Parallel, delayed
    from joblib.externals.loky.process_executor import TerminatedWorkerError

    try:
        done = Parallel(n_jobs=n, backend="loky")(delayed(_call)(fn, x) for x in items)
    except TerminatedWorkerError as exc:
        warnings.warn(f"a worker process died ({str(exc).splitlines()[0]}); the "
                      f"{len(items)} items run again in this process", RuntimeWarning,
                      stacklevel=2)
        return [fn(x) for x in items]
    out = []
    for result, caught in done:
        for message, category in caught:
            warnings.warn(message, category, stacklevel=2)
        out.append(result)
    return out
