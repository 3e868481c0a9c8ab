"""Performance benchmarks of map2map: speed, memory and coverage figures, one script each.

Run them from the repository root as modules (the package must be importable: installed,
or ``PYTHONPATH=src``)::

    python3 -m benchmarks.bench_sim
    python3 -m benchmarks.run sim slam     # several, each in a fresh interpreter

Shared helpers are modules of this package (``benchmarks._sim_plans``,
``benchmarks._profile``). Accuracy experiments live in :mod:`map2map.experiments`.
"""
