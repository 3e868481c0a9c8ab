"""The eq. 3.2 training step with static buffers, ready to run as one CUDA graph replay.

A Model_32 :func:`~map2map.learn.training.step.gan_step` costs ~62-68 ms on an H200 from batch 32
to 256 because it is bound by host overhead (``git show e59abf4^:docs/learn.md``,
"Trained on a GPU": about 2,200 top-level operator calls a step, ~900 of them the
spectral norms' power iterations). A CUDA graph records every kernel of a step once
and replays them with one call. :class:`StaticStep` is that step:

* it owns **static buffers** per (input shape, fade-in or not): ``x``, ``y``, the
  generator's input ``g_input`` (decoder growth), ``alpha`` (a 0-d tensor) and the
  false-target permutation as an int64 **index tensor** (``y.index_select(0, perm)``:
  the same values as ``torch.roll(y, shift)``, without a Python int in the step);
  each call copies its batch in and runs the same eq. 3.2 step, the very code of
  :func:`~map2map.learn.training.step.gan_step`;
* with ``graph=True`` on CUDA, a new shape runs ``warmup`` eager steps on a side stream
  (real training steps: every call is exactly one step), then the next call **captures**
  D step + G step (two forward/backward passes, two Adam steps) in one
  :class:`torch.cuda.CUDAGraph` and replays it; later calls of that shape copy their
  batch in and replay. The returned losses are the graph's static outputs: read (or
  accumulate) them before the next call. One graph per (resolution, batch, fade-in or
  not): the short last batch of an epoch gets its own graph (its size is the same every
  epoch), Model_AB captures again at each stage and once more when a stage's fade-in
  ends (``alpha`` None: the old path no longer runs);
* anything that fails in warm-up or capture makes it **fall back to eager** (with a
  warning); :attr:`StaticStep.mode` says which ran (``"graph"``, ``"eager"``,
  ``"eager (fallback: ...)"``).

What capture needs, and how it is met (PyTorch's "CUDA Graphs" notes):

* Adam with ``capturable=True`` (its ``step`` counters on the device) and the learning
  rate as a 0-d device tensor, so the per-epoch linear decay (thesis 4.2) is a ``fill_``
  the graph sees (:func:`make_capturable`, :func:`~map2map.learn.training.step.set_lr`); torch's
  own LR schedulers also ``fill_`` a tensor lr (since 2.4, pytorch#123753), but the
  trainer sets it itself;
* gradients: set to None before each backward *inside* the capture, so the backward
  allocates them once in the graph's private pool and rewrites them at every replay --
  the docs' whole-network recipe. (Zeroing them in place with ``set_to_none=False``
  would also capture, but then Adam would step parameters that got no gradient this
  step, which eager training skips: Model_AB's blocks of stages not reached.);
* autocast with ``cache_enabled=False`` (:func:`graph_autocast`);
* spectral norm: ``torch.nn.utils.parametrizations.spectral_norm`` updates its ``_u``
  and ``_v`` buffers in place (``out=``), so the power iteration replays correctly;
* a fixed batch size per graph, static input addresses, no host synchronisation in the
  step; single process (under DDP the trainer runs eagerly).

On CPU (or ``graph=False``) it runs eagerly and gives bit-identical weights and losses to
:func:`~map2map.learn.training.step.gan_step` (``tests/test_static_step.py``).

:func:`count_ops` counts the top-level operator calls of a callable with
``torch.profiler`` (the host-overhead measure of ``bench_learn.py --count-ops``).

Examples
--------
>>> import torch
>>> from map2map.learn.training.config import TrainConfig
>>> from map2map.learn.ba.train import build_networks
>>> from map2map.learn.training.loop import place_networks, step_autocast
>>> cfg = TrainConfig(size=16, batch=2, g_channels=4, g_max_channels=8, d_channels=4,
...                   d_layers=2, device="cpu")
>>> nets = build_networks(cfg)
>>> opts = place_networks(nets, torch.device("cpu"), False, cfg)
>>> step = StaticStep(nets, opts, cfg, step_autocast(torch.device("cpu"), False),
...                   freeze=nets[1:])
>>> x = torch.zeros(2, 1, 16, 16); y = torch.ones(2, 1, 16, 16)
>>> out = step(x, y, shift=1)
>>> step.mode, sorted(out)[:3]
('eager', ['d_domain_3_3', 'd_real_fake_3_4', 'fm_3_5'])
"""

from __future__ import annotations

import warnings
from collections import Counter
from dataclasses import dataclass, field

import torch

from .step import gan_step, set_lr

__all__ = ["StaticStep", "make_capturable", "set_lr", "graph_autocast", "count_ops",
           "OpCount"]


def graph_autocast(dev: torch.device, amp: bool):
    """The training step's autocast for capture: as
    :func:`~map2map.learn.training.loop.step_autocast` but ``cache_enabled=False`` (the autocast
    weight cache must not outlive a capture; the values are the same)."""
    if dev.type == "cuda":
        return torch.autocast("cuda", dtype=torch.bfloat16, enabled=amp, cache_enabled=False)
    return torch.autocast("cpu", enabled=False)


def make_capturable(opt: torch.optim.Optimizer, dev: torch.device) -> None:
    """Switch an Adam to what CUDA-graph capture needs: ``capturable=True``, the learning
    rate a 0-d float32 tensor on ``dev`` (same value), existing ``step`` counters moved to
    ``dev``. Moments and weights are untouched; checkpoints store the plain form
    (:func:`~map2map.learn.training.checkpoint.optimizer_tensors`)."""
    for grp in opt.param_groups:
        grp["capturable"] = True
        grp["foreach"] = True
        lr = grp["lr"]
        grp["lr"] = torch.tensor(float(lr), dtype=torch.float32, device=dev)
        for p in grp["params"]:
            st = opt.state.get(p, {})
            if "step" in st:
                st["step"] = st["step"].to(device=dev, dtype=torch.float32)


@dataclass
class _Entry:
    """The static buffers (and graph, once captured) of one input shape."""

    x: torch.Tensor
    y: torch.Tensor
    g_input: torch.Tensor | None
    alpha: torch.Tensor | None
    perm: torch.Tensor
    base: torch.Tensor  # arange(B) on the device: perm = roll(base, shift)
    calls: int = 0
    graph: object = None
    out: dict = field(default_factory=dict)


class StaticStep:
    """One eq. 3.2 step on static buffers, replayed as a CUDA graph (module docstring).

    Parameters
    ----------
    nets : (G, D_d, D_r)
        The networks as run (possibly DDP-wrapped or compiled: then pass
        ``graph=False``).
    opts : (opt_G, opt_D)
        Adam for ``G`` and for both discriminators. With ``graph=True`` on CUDA they are
        made capturable (:func:`make_capturable`) here.
    cfg : TrainConfig
        Loss weights and ``false_targets``.
    autocast : context manager
        The step's autocast (:func:`graph_autocast` when capturing).
    freeze : tuple of modules
        The discriminators (single process), as for :func:`~map2map.learn.training.step.gan_step`.
    graph : bool
        Capture and replay a CUDA graph (CUDA only; elsewhere it runs eagerly).
    warmup : int
        Eager steps per shape before its capture (on a side stream).
    """

    def __init__(self, nets, opts, cfg, autocast, freeze=(), *, graph: bool = False,
                 warmup: int = 3):
        self.g_run, self.dd_run, self.dr_run = nets
        self.opt_g, self.opt_d = opts
        self.cfg, self.autocast, self.freeze = cfg, autocast, tuple(freeze)
        self.warmup = int(warmup)
        self.entries: dict[tuple, _Entry] = {}
        dev = next(self.g_run.parameters()).device
        self.dev = dev
        self.graph = bool(graph) and dev.type == "cuda"
        self.mode = "graph" if self.graph else "eager"
        self.captures = 0
        self.stream = None
        if self.graph:
            for o in opts:
                make_capturable(o, dev)
            # warm-up and capture on one side stream: library handles (cuBLAS/cuDNN
            # workspaces) are made per stream, outside the capture
            self.stream = torch.cuda.Stream(dev)

    # -------------------------------------------------------------------- buffers
    def _entry(self, x, y, alpha, g_input) -> _Entry:
        key = (tuple(x.shape), x.dtype, x.stride(), tuple(y.shape), y.stride(),
               None if g_input is None else (tuple(g_input.shape), g_input.stride()),
               alpha is None)
        e = self.entries.get(key)
        if e is None:
            if any(k[0][-2:] != key[0][-2:] for k in self.entries):
                self.entries.clear()  # a new stage (Model_AB): free the old graphs
            B = x.shape[0]
            base = torch.arange(B, device=x.device)
            e = _Entry(torch.empty_like(x), torch.empty_like(y),
                       None if g_input is None else torch.empty_like(g_input),
                       None if alpha is None else torch.zeros((), device=x.device),
                       base.clone(), base)
            self.entries[key] = e
        return e

    def _load(self, e: _Entry, x, y, shift: int, alpha, g_input) -> None:
        e.x.copy_(x)
        e.y.copy_(y)
        if g_input is not None:
            e.g_input.copy_(g_input)
        if alpha is not None:
            if torch.is_tensor(alpha):
                e.alpha.copy_(alpha)
            else:
                e.alpha.fill_(float(alpha))
        k = e.x.shape[0]
        e.perm.copy_(torch.roll(e.base, shifts=int(shift % k or 1) if k > 1 else 0))

    def _eager(self, e: _Entry) -> dict:
        return gan_step(self.g_run, self.dd_run, self.dr_run, self.opt_g, self.opt_d, e.x,
                        e.y, e.alpha, self.cfg, 0, self.autocast, self.freeze, e.g_input,
                        false_index=e.perm)

    # -------------------------------------------------------------------- the step
    def __call__(self, x: torch.Tensor, y: torch.Tensor, shift: int,
                 alpha: torch.Tensor | float | None = None,
                 g_input: torch.Tensor | None = None) -> dict:
        """Train on the batch ``(x, y)`` (false targets rolled by ``shift``); returns the
        logged values as tensors (static outputs under a graph: read them before the next
        call)."""
        e = self._entry(x, y, alpha, g_input)
        self._load(e, x, y, shift, alpha, g_input)
        if not self.graph:
            return self._eager(e)
        if e.graph is not None:
            e.graph.replay()
            return e.out
        try:
            if e.calls < self.warmup:
                e.calls += 1
                return self._side_stream(e)
            return self._capture(e)
        except Exception as exc:  # noqa: BLE001 - any capture failure: train eagerly
            self._fall_back(exc)
            return self._eager(e)

    def _side_stream(self, e: _Entry) -> dict:
        s = self.stream
        s.wait_stream(torch.cuda.current_stream(self.dev))
        with torch.cuda.stream(s):
            out = self._eager(e)
        torch.cuda.current_stream(self.dev).wait_stream(s)
        return out

    def _capture(self, e: _Entry) -> dict:
        for o in (self.opt_g, self.opt_d):  # the backward allocates them in the graph's pool
            o.zero_grad(set_to_none=True)
        torch.cuda.synchronize(self.dev)
        g = torch.cuda.CUDAGraph()
        with torch.cuda.graph(g, stream=self.stream):
            out = self._eager(e)
        e.graph, e.out = g, {k: v.detach() for k, v in out.items()}
        self.captures += 1
        g.replay()  # the capture recorded this step's kernels without running them
        return e.out

    def _fall_back(self, exc: BaseException) -> None:
        warnings.warn(f"CUDA graph capture failed ({type(exc).__name__}: {exc}); "
                      "training eagerly", RuntimeWarning, stacklevel=3)
        self.graph = False
        self.mode = f"eager (fallback: {type(exc).__name__})"
        for e in self.entries.values():
            e.graph, e.out = None, {}
        for o in (self.opt_g, self.opt_d):
            o.zero_grad(set_to_none=True)
        for net in self.freeze:  # a capture stopped between the D and G steps
            for p in net.parameters():
                p.requires_grad_(True)


@dataclass
class OpCount:
    """Top-level operator calls of one call of a callable (:func:`count_ops`)."""

    top: int
    total: int
    by_name: Counter

    def most_common(self, n: int = 10) -> list[tuple[str, int]]:
        return self.by_name.most_common(n)


def count_ops(fn, *args, **kwargs) -> OpCount:
    """Count the ``aten::`` operator calls of ``fn(*args, **kwargs)`` with
    ``torch.profiler`` (CPU activity): ``top`` counts those with no operator above them
    (each a dispatch from Python or from the autograd engine: what costs host time per
    call, and on CUDA at least one kernel launch), ``total`` also the nested ones;
    ``by_name`` the top-level ones by name.

    Examples
    --------
    >>> c = count_ops(lambda a: (a + 1).sum(), torch.ones(3))
    >>> c.top, sorted(c.by_name)
    (2, ['aten::add', 'aten::sum'])
    """
    from torch.profiler import ProfilerActivity, profile

    with profile(activities=[ProfilerActivity.CPU]) as prof:
        fn(*args, **kwargs)
    events = [ev for ev in prof.events() if ev.name.startswith("aten::")]
    top = Counter(ev.name for ev in events if _top_level(ev))
    return OpCount(sum(top.values()), len(events), top)


def _top_level(ev) -> bool:
    """No ``aten::`` operator above it (``record_function`` ranges such as
    ``Optimizer.step`` and the autograd engine's nodes do not count as parents)."""
    p = ev.cpu_parent
    while p is not None:
        if p.name.startswith("aten::"):
            return False
        p = p.cpu_parent
    return True
