"""Running dataset pairs on a dask.distributed cluster (the optional ``dask`` extra).

The same tasks as the local pool (:func:`map2map.datasets.pair.run_pair` on a
:class:`~map2map.datasets.pair.PairSpec`) are submitted to a scheduler, either an
existing one (``tcp://host:8786``, started with ``dask scheduler`` and ``dask worker``;
every worker needs map2map installed) or a :class:`distributed.LocalCluster` started
here (``"local"``: one single-threaded worker process per requested worker, with
``OMP_NUM_THREADS=1`` and its kin, as Dask's nanny sets them). Results come back to this
process, which writes the pairs and the manifest: workers need no shared file system.
Retries after a worker's death are Dask's
(``distributed.scheduler.allowed-failures``, 3 by default); a pair whose workers kept
dying arrives as :class:`distributed.KilledWorker` and is reported to ``on_crash``.

Scheduling is greedy, like the local pool's: no more tasks are in flight than the
cluster has worker threads (asked again at every completion and every few seconds, so
workers that join are used), and the next task is submitted as soon as one finishes,
before its pair is written. The scheduler therefore always hands the next pair to an
idle worker; submitting every task at once let Dask queue two pairs on one
single-threaded worker while another sat idle at the end of a build (8 pairs: one
worker ran 5, the other 3). It also keeps the scheduler's memory flat for a 35,000-pair
build. Each task carries only the one plan file it uses
(:meth:`~map2map.datasets.plans.PlanSource.only`), not the folder's whole file list.

A LocalCluster runs with :data:`LOCAL_CLUSTER_CONFIG`: without the
``MALLOC_TRIM_THRESHOLD_`` Dask's nanny gives its workers (+20 % CPU per pair), without
the statistical profiler, with slower monitors. Those were the LocalCluster's
overhead over the local pool (+27.7 % wall on 8 pairs; with them gone a pair costs
2.83 CPU s against the pool's 2.71, start-up included: ``benchmarks/bench_dataset.py``).
A cluster of your own gets the same settings from a Dask configuration file in the
directory ``DASK_CONFIG`` names, in the environment of ``dask worker``::

    distributed:
      nanny:
        pre-spawn-environ:
          MALLOC_TRIM_THRESHOLD_: null
      worker:
        profile:
          enabled: false

Workers left at Dask's defaults, or running several threads each (pairs are CPU-bound
Python and numba code: threads of one worker process share its GIL; start workers with
``--nthreads 1 --nworkers K``), get a :class:`DaskWarning`, as does a cluster without
any worker for :data:`NO_WORKER_SECONDS` (the build waits for one). A LocalCluster in
that state (its nannies failed to restart dead workers, seen once on a very loaded
machine) stops the build with an :class:`~map2map.core.errors.InputError` instead: the
same command continues it.

Dask is imported only in this module.

Examples
--------
>>> run_dask([], abs, "local", workers=1, on_result=print, on_crash=print)  # nothing to do
"""

from __future__ import annotations

import logging
import time
import warnings
from collections.abc import Callable, Iterable
from typing import Any

from ..core.errors import InputError, MapWarning
from .pool import TaskQueue

__all__ = ["run_dask", "DaskWarning", "LOCAL_CLUSTER_CONFIG"]


class DaskWarning(MapWarning):
    """A Dask cluster set up in a way that slows pairs down, or without workers (the
    pairs stay right); the command line prints it as one line."""


#: Seconds between two looks at the cluster's size while every slot is busy.
POLL_SECONDS = 2.0
#: Seconds without any worker after which a LocalCluster counts as broken (an error: run
#: the command again to continue) and a cluster of one's own gets a warning (it waits).
NO_WORKER_SECONDS = 60.0
#: Dask settings of a LocalCluster started here. Dask's nanny starts workers with
#: ``MALLOC_TRIM_THRESHOLD_=65536``, which also turns off glibc's dynamic mmap threshold:
#: every large numpy array is then mmapped and faulted in afresh, and a pair took 0.6 CPU s
#: more (+20 %, 29 times the page faults; measured on 3 generated pairs, rbpf, 420 s).
#: Dask's other defaults serve interactive work: a statistical profiler sampling every
#: thread's stack every 10 ms in each worker, an event-loop tick every 20 ms, system and
#: memory monitors every 0.5 and 0.1 s, work stealing every 0.1 s. Idle, that machinery
#: took 0.076 CPU s per second on this machine (2 workers: 3.8 % of its 2 cores, taken
#: from the pairs, and the profiler also takes the GIL from the pair being computed); with
#: these, 0.011. Stealing has nothing to steal here: no worker ever holds a second pair
#: (see ``_run``). ``OMP_NUM_THREADS=1`` and its kin stay as Dask sets them.
LOCAL_CLUSTER_CONFIG = {
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,  # None: not set
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.scheduler.work-stealing": False,
}


def run_dask(
    tasks: Iterable[Any],
    fn: Callable[[Any], Any],
    scheduler: str,
    *,
    workers: int,
    on_result: Callable[[Any, Any, str], None],
    on_crash: Callable[[Any, str], bool],
    key_prefix: str = "map2map-pair",
    connect_timeout: float = 30.0,
) -> None:
    """Run ``fn(task)`` for every task on a Dask cluster.

    Parameters
    ----------
    tasks : iterable
        Tasks with an ``index`` attribute (used in the Dask keys), run in this order.
    fn : callable
        The task function (importable on the workers).
    scheduler : str
        ``"local"`` for a LocalCluster of ``workers`` processes, else a scheduler
        address such as ``tcp://127.0.0.1:8786``.
    workers : int
        Worker processes of a LocalCluster (ignored for an address).
    on_result, on_crash : callable
        As in :func:`map2map.datasets.pool.run_pool`; ``on_crash``'s answer is
        ignored (Dask has already retried).
    key_prefix : str
        Prefix of the task keys (one per dataset, so two datasets never share results).
    connect_timeout : float
        Seconds to wait for the scheduler.

    Raises
    ------
    InputError
        Dask is not installed, or the scheduler cannot be reached.
    """
    try:
        from distributed import Client, KilledWorker, LocalCluster, wait
    except ImportError:
        raise InputError(
            "scheduler", "dask.distributed is not installed (pip install 'map2map[dask]')"
        ) from None
    queue = TaskQueue(tasks)
    if not queue:
        return
    cluster = None
    try:
        if scheduler == "local":
            import dask

            with dask.config.set(LOCAL_CLUSTER_CONFIG):  # the nannies pass it to the workers
                cluster = LocalCluster(n_workers=max(1, int(workers)), threads_per_worker=1,
                                       processes=True, dashboard_address=":0",
                                       silence_logs=logging.ERROR)  # fmt: skip
            # same machine: results come straight from the workers, not via the scheduler
            client = Client(cluster, direct_to_workers=True)
        else:
            _probe(scheduler)
            try:
                client = Client(scheduler, timeout=f"{connect_timeout}s")
            except (OSError, TimeoutError) as exc:
                raise InputError("scheduler", f"cannot reach {scheduler} ({exc})") from None
        try:
            if cluster is None:
                _check_workers(client)
            _run(client, queue, fn, on_result, on_crash, key_prefix, KilledWorker, wait,
                 local=cluster is not None, where=scheduler)
        finally:
            client.close()
    finally:
        if cluster is not None:
            cluster.close()


def _worker_settings() -> dict:
    import os

    import dask

    return {
        "malloc_trim": os.environ.get("MALLOC_TRIM_THRESHOLD_"),
        "profile": bool(dask.config.get("distributed.worker.profile.enabled", True)),
    }


def _check_workers(client) -> None:
    """Warn when a cluster's workers run with the Dask defaults that slow pairs down."""
    try:
        found = client.run(_worker_settings)
    except Exception:  # a worker without map2map, a timeout: the tasks will tell
        return
    trim = sorted({v["malloc_trim"] for v in found.values() if v["malloc_trim"] is not None})
    prof = sum(v["profile"] for v in found.values())
    what = []
    if trim:
        what.append(f"MALLOC_TRIM_THRESHOLD_={trim[0]} (about +20 % CPU per pair)")
    if prof:
        what.append(f"the statistical profiler on ({prof} of {len(found)} workers)")
    if what:
        warnings.warn(
            f"dask workers run with {' and '.join(what)}: give them the settings of "
            "map2map.datasets.dask_backend.LOCAL_CLUSTER_CONFIG (README: Paired datasets)",
            DaskWarning, stacklevel=3)  # fmt: skip


def _threads(client, warned: set) -> int:
    """Worker threads of the cluster now (0 while it has no worker)."""
    nthreads = client.nthreads()
    if "threads" not in warned and any(n > 1 for n in nthreads.values()):
        warned.add("threads")
        warnings.warn(
            f"dask workers run {max(nthreads.values())} threads each: pairs are CPU-bound and "
            "share one process's GIL; start workers with --nthreads 1 --nworkers K",
            DaskWarning, stacklevel=4)  # fmt: skip
    return sum(nthreads.values())


def _run(
    client, queue: TaskQueue, fn, on_result, on_crash, key_prefix, killed_worker, wait, *,
    local: bool = False, where: str = "", no_worker_s: float | None = None,
) -> None:  # fmt: skip
    in_flight: dict[Any, Any] = {}  # future -> task
    warned: set[str] = set()
    no_worker_s = NO_WORKER_SECONDS if no_worker_s is None else no_worker_s
    seen = time.monotonic()  # when the cluster last had a worker

    def top_up() -> None:
        nonlocal seen
        threads = _threads(client, warned)
        now = time.monotonic()
        if threads:
            seen = now
        elif now - seen > no_worker_s:
            if local:
                raise InputError("scheduler", f"the LocalCluster has had no worker for "
                                 f"{now - seen:.0f} s (they died and were not restarted); "
                                 "run the same command again to continue")  # fmt: skip
            if "empty" not in warned:
                warned.add("empty")
                warnings.warn(f"no dask worker at {where} for {now - seen:.0f} s; waiting "
                              f"(start one: dask worker {where} --nthreads 1)", DaskWarning,
                              stacklevel=3)  # fmt: skip
        while queue and len(in_flight) < max(1, threads):  # no worker: one task waits
            t = queue.popleft()
            in_flight[client.submit(fn, t, key=f"{key_prefix}-{t.index}", pure=False)] = t

    try:
        while queue or in_flight:
            top_up()
            try:
                done = wait(list(in_flight), timeout=POLL_SECONDS,
                            return_when="FIRST_COMPLETED").done  # fmt: skip
            except TimeoutError:
                continue  # every slot still busy: look at the cluster's size again
            # Fetch the finished pairs and release them *before* the next pairs start: a
            # result still held by a worker is lost if the next pair kills that worker,
            # and Dask then recomputes it; while recomputed it counts as running on the
            # next worker that dies, and can be declared a killer (KilledWorker) itself.
            finished = []
            for fut in done:
                task = in_flight.pop(fut)
                try:
                    finished.append((task, fut.result(), None))
                except killed_worker as exc:
                    finished.append((task, None, _killed_reason(exc)))
                fut.release()
            top_up()  # the next pairs start before these are written
            for task, result, crash in finished:
                if crash is None:
                    on_result(task, result, "dask")
                else:
                    on_crash(task, crash)
    finally:
        for fut in in_flight:  # interrupted: do not leave pairs running on the cluster
            fut.cancel()


def _killed_reason(exc) -> str:
    """One line for :class:`distributed.KilledWorker` (its own text is a paragraph)."""
    try:
        times = int(exc.allowed_failures) + 1
        last = getattr(exc.last_worker, "address", exc.last_worker)
    except (AttributeError, IndexError, TypeError, ValueError):
        return f"dask workers died running it ({exc})"
    return f"dask workers died running it ({times} workers, the last {last})"


def _probe(address: str, timeout: float = 5.0) -> None:
    """Fail fast (one line) when nothing listens at a ``tcp://host:port`` address."""
    import socket
    from urllib.parse import urlsplit

    u = urlsplit(address if "://" in address else f"tcp://{address}")
    if u.scheme != "tcp" or not u.hostname:
        return  # other protocols (tls, ucx, inproc): let Dask try
    try:
        with socket.create_connection((u.hostname, u.port or 8786), timeout=timeout):
            pass
    except OSError as exc:
        raise InputError("scheduler", f"cannot reach {address} ({exc})") from None
