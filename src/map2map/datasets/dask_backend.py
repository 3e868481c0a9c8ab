"""Running dataset pairs on a dask.distributed cluster (the optional ``dask`` extra).

The same tasks as the local pool (:func:`map2map.datasets.pair.run_pair` on a
:class:`~map2map.datasets.pair.PairSpec`) are submitted to a scheduler, either an
existing one (``tcp://host:8786``, started with ``dask scheduler`` and ``dask worker``;
every worker needs map2map installed) or a :class:`distributed.LocalCluster` started
here (``"local"``: one single-threaded worker process per requested worker). Results
come back to this process, which writes the pairs and the manifest: workers need no
shared file system. Retries after a worker's death and work stealing are Dask's
(``distributed.scheduler.allowed-failures``, 3 by default); a pair whose workers kept
dying arrives as :class:`distributed.KilledWorker` and is reported to ``on_crash``.

Dask is imported only in this module.

Examples
--------
>>> run_dask([], abs, "local", workers=1, on_result=print, on_crash=print)  # nothing to do
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

from ..core.errors import InputError

__all__ = ["run_dask"]


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
        Tasks with an ``index`` attribute (used in the Dask keys).
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
        from distributed import Client, KilledWorker, LocalCluster, as_completed
    except ImportError:
        raise InputError(
            "--scheduler", "dask.distributed is not installed (pip install 'map2map[dask]')"
        ) from None
    tasks = list(tasks)
    if not tasks:
        return
    cluster = None
    try:
        if scheduler == "local":
            cluster = LocalCluster(n_workers=max(1, int(workers)), threads_per_worker=1,
                                   processes=True, dashboard_address=":0")  # fmt: skip
            client = Client(cluster)
        else:
            _probe(scheduler)
            try:
                client = Client(scheduler, timeout=f"{connect_timeout}s")
            except (OSError, TimeoutError) as exc:
                raise InputError("--scheduler", f"cannot reach {scheduler} ({exc})") from None
        try:
            by_key = {}
            futures = []
            for t in tasks:
                fut = client.submit(fn, t, key=f"{key_prefix}-{t.index}", pure=False)
                by_key[fut.key] = t
                futures.append(fut)
            done = as_completed(futures)
            del futures  # as_completed holds them; each is dropped once handled
            for fut in done:
                task = by_key.pop(fut.key)
                try:
                    result = fut.result()
                except KilledWorker as exc:
                    on_crash(task, f"dask workers died running it ({exc})")
                else:
                    on_result(task, result, "dask")
                fut.release()
        finally:
            client.close()
    finally:
        if cluster is not None:
            cluster.close()


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
        raise InputError("--scheduler", f"cannot reach {address} ({exc})") from None
