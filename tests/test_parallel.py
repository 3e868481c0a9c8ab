"""Per-item work in worker processes (:mod:`map2map.core.parallel`): the results, their
order and the workers' warnings are those of the loop in the caller."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from map2map.core.parallel import default_workers, process_map


def _warn_odd(x: int) -> int:
    if x % 2:
        warnings.warn(f"odd {x}", UserWarning, stacklevel=1)
    return x * x


def test_results_and_their_order_do_not_depend_on_the_workers():
    items = list(range(40))
    one = process_map(np.sqrt, items, workers=1)
    two = process_map(np.sqrt, items, workers=2, min_items=2)
    assert two == one == [np.sqrt(i) for i in items]


def _pid(_: int) -> int:
    import os

    return os.getpid()


def test_the_items_run_in_other_processes_from_min_items_on():
    import os

    assert set(process_map(_pid, range(3), workers=2)) == {os.getpid()}   # < min_items
    pids = set(process_map(_pid, range(40), workers=2, min_items=8))
    assert os.getpid() not in pids and 1 <= len(pids) <= 2


def test_a_workers_warnings_are_raised_in_the_caller_in_order():
    with pytest.warns(UserWarning) as got:
        out = process_map(_warn_odd, range(20), workers=2, min_items=2)
    assert out == [i * i for i in range(20)]
    assert [str(w.message) for w in got] == [f"odd {i}" for i in range(1, 20, 2)]


def test_few_items_or_one_worker_run_in_the_caller(monkeypatch):
    import joblib

    def no_pool(*a, **k):
        raise AssertionError("a pool was started")

    monkeypatch.setattr(joblib, "Parallel", no_pool)
    assert process_map(abs, [-1, -2, -3], workers=4) == [1, 2, 3]      # < min_items
    assert process_map(abs, range(-30, 0), workers=1)[:2] == [30, 29]
    assert 1 <= default_workers() <= 8
