"""Where a training step's device time goes: ``torch.profiler`` over a few steps, the
kernels (or, on a CPU, the operators) sorted by their own time. Shared by
``bench_learn --profile`` and ``bench_ab --profile`` (import it as
``from benchmarks._profile import print_top`` when they run as ``python3 -m benchmarks.X``).

Session 12 found this way that one kernel (PyTorch's NCHW bilinear upsampling) took 75 %
of a Model_32 step on an H200 (docs/autocorrect.md, "Measured on a GPU: the graph, and the
kernel that held the step").
"""

from __future__ import annotations

import torch


def print_top(step, steps: int, device: torch.device, rows: int = 25, title: str = "") -> None:
    """Run ``step(i)`` for ``steps`` steps under the profiler and print the ``rows``
    entries with the most self time (CUDA kernels on a GPU, operators on a CPU)."""
    from torch.profiler import ProfilerActivity, profile

    cuda = device.type == "cuda"
    acts = [ProfilerActivity.CUDA] if cuda else [ProfilerActivity.CPU]
    with profile(activities=acts) as prof:
        for i in range(steps):
            step(i)
        if cuda:
            torch.cuda.synchronize(device)
    key = "self_cuda_time_total" if cuda else "self_cpu_time_total"
    print(f"profile{': ' + title if title else ''} ({steps} steps, sorted by {key})")
    print(prof.key_averages().table(sort_by=key, row_limit=rows, max_name_column_width=80),
          flush=True)
