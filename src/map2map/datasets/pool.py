"""Local process pool for dataset builds: long-lived workers that notice a worker's death.

Each worker process imports the package once and runs many pairs (numba's compiled
kernels stay warm). Unlike :class:`concurrent.futures.ProcessPoolExecutor`, whose pool
breaks as a whole when one worker dies, this pool knows which pair each worker holds:
when a worker dies (``os._exit``, a segfault, the OOM killer) only that pair is reported
(``on_crash``), a fresh worker takes its place, and the pair is retried if ``on_crash``
says so. Tasks and results travel through one pipe per worker.

Examples
--------
>>> got = []
>>> run_pool([1, 2, 3], abs, 1, on_result=lambda t, r, w: got.append(r),
...          on_crash=lambda t, why: False, start_method="fork")
>>> sorted(got)
[1, 2, 3]
"""

from __future__ import annotations

import multiprocessing as mp
import signal
from collections import deque
from collections.abc import Callable, Iterable
from multiprocessing.connection import wait
from typing import Any

__all__ = ["run_pool", "death_reason", "TaskQueue"]


class TaskQueue:
    """The tasks still to hand out: drawn from an iterable only when needed (a build of
    many pairs makes its tasks one at a time), with the tasks to run again in front.

    Examples
    --------
    >>> q = TaskQueue(iter(range(3)))
    >>> q.popleft(), bool(q)
    (0, True)
    >>> q.appendleft(0)
    >>> [q.popleft() for _ in range(3)], bool(q)
    ([0, 1, 2], False)
    """

    def __init__(self, tasks: Iterable[Any]):
        self._it = iter(tasks)
        self._front: deque = deque()

    def __bool__(self) -> bool:
        if not self._front:
            try:
                self._front.append(next(self._it))
            except StopIteration:
                return False
        return True

    def popleft(self) -> Any:
        if not self:
            raise IndexError("no task left")
        return self._front.popleft()

    def appendleft(self, task: Any) -> None:
        self._front.appendleft(task)


def _quiet_bars() -> None:
    """Give tqdm a thread lock in a worker. Its default lock holds a multiprocessing
    semaphore, made by the first bar (a disabled one too, as the simulator's); a worker
    killed mid-pair (Ctrl-C) cannot release it, and the resource tracker then warned of
    "leaked semaphore objects" when the build stopped. Workers draw no bars."""
    import threading

    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover - tqdm is a dependency
        return
    tqdm.set_lock(threading.RLock())


def _worker_main(conn, fn) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C
    _quiet_bars()
    while True:
        try:
            task = conn.recv()
        except (EOFError, OSError):
            return
        if task is None:
            return
        try:
            conn.send(fn(task))
        except (BrokenPipeError, OSError):
            return


def death_reason(exitcode: int | None) -> str:
    """Words for a worker's exit code (negative: killed by that signal).

    Examples
    --------
    >>> death_reason(-11), death_reason(3)
    ('worker died (killed by SIGSEGV)', 'worker died (exit code 3)')
    """
    if exitcode is not None and exitcode < 0:
        try:
            name = signal.Signals(-exitcode).name
        except ValueError:
            name = f"signal {-exitcode}"
        return f"worker died (killed by {name})"
    return f"worker died (exit code {exitcode})"


class _Worker:
    def __init__(self, ctx, fn, name: str):
        self.conn, child = ctx.Pipe()
        self.proc = ctx.Process(target=_worker_main, args=(child, fn), name=name, daemon=True)
        self.proc.start()
        child.close()
        self.name = name
        self.task: Any = None
        self.asked = False

    def ask_to_stop(self) -> None:
        if self.asked:
            return
        self.asked = True
        try:
            self.conn.send(None)
        except (BrokenPipeError, OSError):
            pass

    def stop(self, timeout: float = 5.0) -> None:
        self.ask_to_stop()
        self.proc.join(timeout)
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join(timeout)
        self.conn.close()


def run_pool(
    tasks: Iterable[Any],
    fn: Callable[[Any], Any],
    workers: int,
    *,
    on_result: Callable[[Any, Any, str], None],
    on_crash: Callable[[Any, str], bool],
    start_method: str = "spawn",
) -> None:
    """Run ``fn(task)`` for every task on ``workers`` processes.

    Parameters
    ----------
    tasks : iterable
        Picklable tasks; ``fn`` must be importable by name in a fresh process.
    fn : callable
        What a worker runs per task; its return value goes to ``on_result``.
    workers : int
        Number of worker processes (>= 1).
    on_result : callable ``(task, result, worker name)``
        Called in this process, in completion order.
    on_crash : callable ``(task, reason) -> bool``
        Called when the worker holding ``task`` died; return True to run it again.
    start_method : str
        multiprocessing start method (``spawn`` default: no state inherited).
    """
    if workers < 1:
        raise ValueError("workers must be >= 1")
    ctx = mp.get_context(start_method)
    queue = TaskQueue(tasks)
    pool: list[_Worker] = []
    serial = 0
    try:
        while queue or any(w.task is not None for w in pool):
            # hand out work; start workers lazily, never more than there are tasks
            for w in pool:
                if w.task is None and queue:
                    w.task = queue.popleft()
                    w.conn.send(w.task)
            while queue and len(pool) < workers:
                serial += 1
                w = _Worker(ctx, fn, f"local-{serial}")
                pool.append(w)
                w.task = queue.popleft()
                w.conn.send(w.task)
            busy = [w for w in pool if w.task is not None]
            ready = set(wait([w.conn for w in busy] + [w.proc.sentinel for w in busy]))
            for w in busy:
                if w.conn in ready or w.proc.sentinel in ready:
                    result, got = None, False
                    if w.conn.poll():
                        try:
                            result, got = w.conn.recv(), True
                        except (EOFError, OSError):
                            got = False
                    task, w.task = w.task, None
                    if got:
                        if queue:  # the worker starts its next pair while this one is written
                            w.task = queue.popleft()
                            w.conn.send(w.task)
                        on_result(task, result, w.name)
                        continue
                    w.proc.join(5.0)
                    reason = death_reason(w.proc.exitcode)
                    pool.remove(w)
                    w.conn.close()
                    if on_crash(task, reason):
                        queue.appendleft(task)
    finally:
        for w in pool:  # all exit at once (an interpreter's exit takes ~0.5 s)
            if w.task is not None:  # interrupted: do not wait for a long pair
                w.proc.kill()
            else:
                w.ask_to_stop()
        for w in pool:
            w.stop()
