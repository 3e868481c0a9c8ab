"""The CUDA-graph-ready training step (:mod:`map2map.learn.training.static_step`): run eagerly it is
bit for bit today's ``gan_step`` (Model_BA; Model_AB with a fade-in alpha, dropout and
the decoder growth's full-size input), a training run with ``cuda_graph`` equals one
without, a capture failure falls back to eager steps, the op counter counts. On a CUDA
machine one more test checks the graph replay against eager steps."""

from __future__ import annotations

import warnings

import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("safetensors")

from test_learn_ab import _pairs  # noqa: E402  (boxes with walls, shifted speckled copies)

from map2map.learn.ab.config import ABConfig  # noqa: E402
from map2map.learn.ab.model import build_ab_networks  # noqa: E402
from map2map.learn.ab.train import train_ab  # noqa: E402
from map2map.learn.ba.model import build_networks  # noqa: E402
from map2map.learn.ba.train import train_ba  # noqa: E402
from map2map.learn.training.checkpoint import load_checkpoint  # noqa: E402
from map2map.learn.training.config import TrainConfig  # noqa: E402
from map2map.learn.training.loop import place_networks, step_autocast  # noqa: E402
from map2map.learn.training.static_step import StaticStep, count_ops  # noqa: E402
from map2map.learn.training.step import gan_step  # noqa: E402

CPU = torch.device("cpu")


pytestmark = pytest.mark.usefixtures("one_torch_thread")


def _batches(n_steps, batch, size, seed=0):
    gen = torch.Generator().manual_seed(seed)
    return [tuple(torch.randint(0, 3, (batch, 1, size, size), generator=gen).float() - 1
                  for _ in range(2)) for _ in range(n_steps)]


def _state(nets, opts):
    """Every tensor training touches: weights, spectral-norm vectors, Adam moments."""
    out = {}
    for name, net in zip(("G", "D_d", "D_r"), nets, strict=True):
        out.update({f"{name}.{k}": v.clone() for k, v in net.state_dict().items()})
    for name, o in zip(("opt_G", "opt_D"), opts, strict=True):
        for i, st in enumerate(o.state.values()):
            out.update({f"{name}.{i}.{k}": torch.as_tensor(v).clone() for k, v in st.items()})
    return out


def _same(a: dict, b: dict):
    assert a.keys() == b.keys()
    for k in a:
        assert torch.equal(a[k], b[k]), k


def _run(build, cfg, batches, static: bool, alphas, g_inputs=None, dev=CPU, graph=False):
    torch.manual_seed(123)  # dropout (Model_AB) draws from the global generator
    nets = build(cfg)
    opts = place_networks(nets, dev, False, cfg)
    ac = step_autocast(dev, False)
    freeze = nets[1:]
    step = StaticStep(nets, opts, cfg, ac, freeze, graph=graph) if static else None
    losses = []
    for i, (x, y) in enumerate(batches):
        x, y = x.to(dev), y.to(dev)
        a = alphas[i]
        a = None if a is None else torch.tensor(a, device=dev)
        gi = None if g_inputs is None else g_inputs[i].to(dev)
        shift = 1 + 3 * i
        if static:
            out = step(x, y, shift, a, gi)
        else:
            out = gan_step(*nets, *opts, x, y, a, cfg, shift, ac, freeze, gi)
        losses.append({k: v.detach().clone() for k, v in out.items()})
    return _state(nets, opts), losses, step


def test_static_step_eager_is_gan_step_bit_for_bit_model_ba():
    cfg = TrainConfig(size=16, batch=4, g_channels=8, g_max_channels=16, d_channels=8,
                      d_layers=2, device="cpu")
    batches = _batches(4, 4, 16)
    batches.append(tuple(t[:3] for t in _batches(1, 4, 16, seed=1)[0]))  # a short batch
    alphas = [None] * 5
    s0, l0, _ = _run(build_networks, cfg, batches, False, alphas)
    s1, l1, step = _run(build_networks, cfg, batches, True, alphas)
    _same(s0, s1)
    for a, b in zip(l0, l1, strict=True):
        _same(a, b)
    assert step.mode == "eager" and len(step.entries) == 2  # full and short batch


@pytest.mark.parametrize("growth", ["full", "decoder"])
def test_static_step_eager_is_gan_step_bit_for_bit_model_ab_with_alpha(growth):
    cfg = ABConfig(schedule=((8, 1), (16, 1)), batch=3, g_channels=8, g_max_channels=16,
                   d_channels=8, d_layers=1, d_scales=2, device="cpu", growth=growth)
    batches = _batches(5, 3, 16)
    alphas = [0.2, 0.5, 0.9, None, None]  # fading in, then the fade is over
    g_inputs = [x for x, _ in batches] if growth == "decoder" else None
    s0, l0, _ = _run(build_ab_networks, cfg, batches, False, alphas, g_inputs)
    s1, l1, step = _run(build_ab_networks, cfg, batches, True, alphas, g_inputs)
    _same(s0, s1)
    for a, b in zip(l0, l1, strict=True):
        _same(a, b)
    assert len(step.entries) == 2  # with and without alpha: two static steps


def _run_tensors(run):
    t, st = load_checkpoint(run / "last.safetensors")
    return t, [{k: v for k, v in r.items() if k not in ("img_per_s", "epoch_s", "step")}
               for r in st["history"]], st


def test_training_with_cuda_graph_on_cpu_equals_training_without(tmp_path):
    pairs = _pairs(9)  # 7 train pairs in batches of 3: a short last batch each epoch
    for trainer, cfg in (
            (train_ba, dict(size=16, epochs=2, batch=3, g_channels=8, g_max_channels=16,
                            d_channels=8, d_layers=2, samples=1, device="cpu")),
            (train_ab, dict(schedule=((8, 1), (16, 2)), batch=3, g_channels=8,
                            g_max_channels=16, d_channels=8, d_layers=1, d_scales=2,
                            fade_batches=2, samples=1, device="cpu"))):
        ctype = TrainConfig if trainer is train_ba else ABConfig
        runs = []
        for graph in (False, True):
            run = tmp_path / f"{trainer.__name__}_{graph}"
            trainer(pairs, run, ctype(**cfg, cuda_graph=graph), progress=False, figures=False)
            runs.append(_run_tensors(run))
        (t0, h0, st0), (t1, h1, st1) = runs
        _same(t0, t1)
        assert h0 == h1
        assert st0["opt_G"] == st1["opt_G"]  # the plain optimiser groups either way
        assert st1["history"][-1]["step"] == "eager"  # on CPU the static step runs eagerly
        assert st1["config"]["cuda_graph"] and not st0["config"]["cuda_graph"]


def test_capture_failure_falls_back_to_eager_steps(monkeypatch):
    cfg = TrainConfig(size=16, batch=4, g_channels=8, g_max_channels=16, d_channels=8,
                      d_layers=2, device="cpu")
    batches = _batches(3, 4, 16)
    s0, l0, _ = _run(build_networks, cfg, batches, False, [None] * 3)

    def broken(self, e):  # fails half-way, the discriminators frozen, as a capture may
        for net in self.freeze:
            for p in net.parameters():
                p.requires_grad_(False)
        raise RuntimeError("operation not permitted when stream is capturing")

    monkeypatch.setattr(StaticStep, "_side_stream", broken)
    monkeypatch.setattr(StaticStep, "__init__", _forced_graph_init)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        s1, l1, step = _run(build_networks, cfg, batches, True, [None] * 3)
    assert any("training eagerly" in str(x.message) for x in w)
    assert step.mode == "eager (fallback: RuntimeError)" and not step.graph
    _same(s0, s1)


_real_init = StaticStep.__init__


def _forced_graph_init(self, *a, **k):
    _real_init(self, *a, **k)
    self.graph, self.mode = True, "graph"  # as on CUDA, without a GPU


def test_count_ops_counts_the_step_and_the_static_step_adds_only_its_copies():
    cfg = TrainConfig(size=16, batch=2, g_channels=8, g_max_channels=16, d_channels=8,
                      d_layers=2, device="cpu")
    nets = build_networks(cfg)
    opts = place_networks(nets, CPU, False, cfg)
    ac = step_autocast(CPU, False)
    x, y = _batches(1, 2, 16)[0]
    step = StaticStep(nets, opts, cfg, ac, nets[1:])
    step(x, y, 1)
    eager = count_ops(gan_step, *nets, *opts, x, y, None, cfg, 1, ac, nets[1:])
    static = count_ops(step, x, y, 1)
    assert eager.top > 500 and eager.total > eager.top
    assert eager.by_name["aten::conv2d"] == static.by_name["aten::conv2d"]
    assert 0 <= static.top - eager.top <= 6  # copies in, the rolled index


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs CUDA")
def test_cuda_graph_replay_matches_eager_steps():
    dev = torch.device("cuda")
    cfg = TrainConfig(size=16, batch=4, g_channels=8, g_max_channels=16, d_channels=8,
                      d_layers=2, device="cuda")
    batches = _batches(8, 4, 16)
    alphas = [None] * 8
    s0, l0, _ = _run(build_networks, cfg, batches, True, alphas, dev=dev)
    s1, l1, step = _run(build_networks, cfg, batches, True, alphas, dev=dev, graph=True)
    assert step.mode == "graph" and step.captures == 1
    for k in s0:
        torch.testing.assert_close(s0[k].float(), s1[k].float(), rtol=1e-3, atol=1e-5,
                                   msg=k)


# ----------------------------------------------- the graph path's control flow, emulated
class _FakeStream:
    def wait_stream(self, other):
        pass


class _FakeGraph:
    """A 'CUDA graph' on the CPU: the capture runs the step and then undoes it (a real
    capture records kernels without running them); replay runs the recorded step again
    and writes its values into the captured output tensors (a real replay rewrites the
    same memory)."""

    def __init__(self):
        self.fn = None

    def replay(self):
        self.fn()


class _Emulation:
    """Patches torch.cuda's stream and graph calls and StaticStep so the warm-up / capture /
    replay logic runs on the CPU with the semantics above."""

    def __init__(self, monkeypatch):
        import contextlib

        import map2map.learn.training.static_step as SS

        self.captures, self.replays = 0, 0
        real_eager = SS.StaticStep._eager
        emu = self

        def eager(step, e):
            emu.last = (step, e)
            return real_eager(step, e)

        @contextlib.contextmanager
        def graph(g, stream=None):
            emu.last = None
            saved = [t.detach().clone() for t in emu.tensors()], torch.get_rng_state()
            yield
            step, e = emu.last
            for t, v in zip(emu.tensors(), saved[0], strict=True):  # undo: not executed
                t.data.copy_(v)
            torch.set_rng_state(saved[1])
            emu.captures += 1

            def run():
                emu.replays += 1
                out = real_eager(step, e)
                for k, v in out.items():
                    e.out[k].copy_(v.detach())

            g.fn = run

        def init(step, *a, **k):
            real_init(step, *a, **k)
            step.graph, step.mode, step.stream = True, "graph", _FakeStream()
            emu.step = step

        real_init = SS.StaticStep.__init__
        monkeypatch.setattr(SS.StaticStep, "_eager", eager)
        monkeypatch.setattr(SS.StaticStep, "__init__", init)
        monkeypatch.setattr(torch.cuda, "graph", graph)
        monkeypatch.setattr(torch.cuda, "CUDAGraph", _FakeGraph)
        monkeypatch.setattr(torch.cuda, "current_stream", lambda dev=None: _FakeStream())
        monkeypatch.setattr(torch.cuda, "stream", lambda s: contextlib.nullcontext())
        monkeypatch.setattr(torch.cuda, "synchronize", lambda dev=None: None)

    def tensors(self):
        """Everything a step changes: weights, buffers, Adam's state."""
        s = self.step
        out = []
        for net in (s.g_run, s.dd_run, s.dr_run):
            out += list(net.parameters()) + list(net.buffers())
        for o in (s.opt_g, s.opt_d):
            for st in o.state.values():
                out += [v for v in st.values() if torch.is_tensor(v)]
        return out


@pytest.mark.parametrize("trainer", ["ba", "ab"])
def test_graph_path_control_flow_emulated_on_cpu_trains_as_eager(monkeypatch, tmp_path, trainer):
    """Warm-up on the side stream, one capture per shape (full and short batch; Model_AB:
    per stage and fade or not), replays after: with a CPU stand-in for the graph, the run
    equals the eager one bit for bit and every step after the warm-up is a replay."""
    pairs = _pairs(9)  # 7 train pairs in batches of 3: 2 full + 1 short an epoch
    if trainer == "ba":
        run_fn, cfg = train_ba, TrainConfig(
            size=16, epochs=4, batch=3, g_channels=8, g_max_channels=16, d_channels=8,
            d_layers=2, samples=1, device="cpu")
    else:
        run_fn, cfg = train_ab, ABConfig(
            schedule=((8, 1), (16, 5)), batch=3, g_channels=8, g_max_channels=16,
            d_channels=8, d_layers=1, d_scales=2, fade_batches=6, samples=1, device="cpu")
    run_fn(pairs, tmp_path / "eager", cfg, progress=False, figures=False)
    emu = _Emulation(monkeypatch)
    cfg.cuda_graph = True
    run_fn(pairs, tmp_path / "graph", cfg, progress=False, figures=False)
    (t0, h0, _), (t1, h1, st1) = (_run_tensors(tmp_path / r) for r in ("eager", "graph"))
    _same(t0, t1)
    assert h0 == h1
    assert {r["step"] for r in st1["history"]} == {"graph"}
    if trainer == "ba":  # full batch: 8 calls = 3 warm-up + capture + 4; short: 3 + capture
        assert (emu.captures, emu.replays) == (2, 6)
    else:  # 8 px: 3 batches, all warm-up; 16 px: 15 batches, 6 fading then 9 without
        # fade: full (4 calls) 3 + capture, short (2) warm-up; after: full (6) 3 + capture
        # + 2, short (3) 3 warm-up
        assert (emu.captures, emu.replays) == (2, 4)
