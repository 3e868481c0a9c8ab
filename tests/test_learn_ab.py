"""Model_AB / Model_prog: growth and fade-in (shapes at each stage, alpha schedule, the
fade's end points), exact resume at the right resolution and alpha, the command lines,
synthesize's frame and hypotheses."""

from __future__ import annotations

import os
import signal
import warnings

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("safetensors")

import torch.nn.functional as F  # noqa: E402

from map2map.cli.main import main  # noqa: E402
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN  # noqa: E402
from map2map.datasets.packed import PackedPairs, save_packed  # noqa: E402
from map2map.learn.ab import train as TA  # noqa: E402
from map2map.learn.ab.config import TABLE_5_2, ABConfig, fade_steps, parse_schedule, stage_of  # noqa: E402
from map2map.learn.ab.model import build_ab_networks  # noqa: E402
from map2map.learn.nets.progressive import ProgMultiScaleDiscriminator, StochasticUNet, fade_alpha  # noqa: E402

pytestmark = pytest.mark.usefixtures("one_torch_thread")


#: two stages, 8 then 16 px; 6 train pairs in batches of 2: 3 batches per epoch
TINY = dict(schedule=((8, 1), (16, 2)), batch=2, g_channels=8, g_max_channels=16,
            d_channels=8, d_layers=1, d_scales=2, fade_batches=4, samples=2)


def _pairs(n=8, size=16, seed=0) -> PackedPairs:
    """Plans (A): boxes with a wall; SLAM maps (B): shifted, speckled copies."""
    rng = np.random.default_rng(seed)
    a = np.full((n, size, size), UNKNOWN, np.uint8)
    for i in range(n):
        r0, c0 = rng.integers(1, 4, 2)
        a[i, r0:size - 2, c0:size - 2] = FREE
        a[i, r0, c0:size - 2] = OCCUPIED
        a[i, r0:size - 2, rng.integers(c0 + 2, size - 3)] = OCCUPIED
    b = np.roll(a, 1, axis=1)
    b[rng.random(b.shape) < 0.05] = UNKNOWN
    split = np.array(["train"] * (n - 2) + ["val", "test"])
    return PackedPairs(a, b, np.array([f"p{i}" for i in range(n)]), split, {"seed": seed})


# ------------------------------------------------------------------------- schedule
def test_table_5_2_schedule_and_table_5_1_batches_are_the_defaults():
    cfg = ABConfig()
    assert cfg.schedule == TABLE_5_2 and cfg.epochs == 205 and cfg.size == 256
    assert cfg.batch_rate == 1.0
    assert [cfg.stage_batch(r) for r, _ in cfg.schedule] == [64, 32, 16, 4]
    firsts = [e for e in range(205) if e == 0 or stage_of(e, cfg.schedule)[1]
              != stage_of(e - 1, cfg.schedule)[1]]
    assert firsts == [0, 15, 45, 105]
    assert stage_of(300, cfg.schedule)[1] == 256          # beyond the table: last stage
    assert parse_schedule("8:7,16:15,32:15")[0] == (8, 7)
    for bad in ("32:15,128:60", "30:2", "32:0", "32"):
        with pytest.raises(ValueError):
            parse_schedule(bad)
    # fade length: half the new stage's batches by default, stated in batches
    assert fade_steps(0, 66, cfg) == 0
    assert fade_steps(1, 132, cfg) == 1980                # 0.5 * 30 epochs * 132 batches
    assert fade_steps(1, 132, ABConfig(fade_batches=10)) == 10


def test_alpha_goes_from_zero_to_one_in_the_stated_batches():
    steps = 8
    a = [fade_alpha(s, steps) for s in range(12)]
    assert a[0] == 0.0 and a[steps] == 1.0 and a[-1] == 1.0
    assert np.all(np.diff(a[:steps + 1]) == pytest.approx(1 / steps))
    assert fade_alpha(0, 0) == 1.0


# ------------------------------------------------------------------------- networks
def test_shapes_at_each_stage_and_unreached_blocks_get_no_gradient():
    cfg = ABConfig(schedule=((8, 1), (16, 1), (32, 1)), g_channels=8, g_max_channels=16,
                   d_channels=8, d_layers=1, d_scales=2)
    g, dd, dr = build_ab_networks(cfg)
    for r in (8, 16, 32):
        x = torch.rand(2, 1, r, r) * 2 - 1
        for alpha in (None, torch.tensor(0.3)):
            y = g(x, alpha)
            assert y.shape == (2, 1, r, r)
            outs = dd(torch.cat([x, y], 1), alpha)
            # scale 1 at r, scale 2 at r/2; one stride-2 layer beyond the growth blocks
            assert [o[-1].shape[-1] for o in outs] == [4, 2]
            assert [tuple(o[-1].shape[-2:]) for o in outs] == \
                [tuple(o[-1].shape[-2:]) for o in dr(y, alpha)]
    with pytest.raises(ValueError):
        g(torch.zeros(1, 1, 4, 4))
    with pytest.raises(ValueError):
        dd(torch.zeros(1, 2, 64, 64))
    # a step at the first stage touches none of the finer blocks
    g.zero_grad()
    dr.zero_grad()
    x = torch.rand(2, 1, 8, 8)
    sum(o[-1].sum() for o in dr(g(x))).backward()
    assert g.from_map["16"][0].weight.grad is None and g.up["32"][0].weight.grad is None
    assert dr.discs[0].from_map["16"][0].parametrizations.weight.original.grad is None
    assert g.from_map["8"][0].weight.grad is not None


def test_fade_end_points_are_the_old_and_the_new_network():
    """alpha 0: exactly the previous stage's path (area-reduced input, upsampled output);
    alpha 1: the new stage's network."""
    torch.manual_seed(0)
    g = StochasticUNet(size=32, channels=8, max_channels=16, min_size=8, dropout=0.0).eval()
    d = ProgMultiScaleDiscriminator(2, channels=8, n_layers=1, scales=2, size=32, min_size=8).eval()
    x = torch.rand(3, 1, 16, 16) * 2 - 1
    small = F.avg_pool2d(x, 2)
    with torch.no_grad():
        old = g(small)
        up = torch.tanh(F.interpolate(torch.atanh(old.clamp(-0.999999, 0.999999)),
                                      scale_factor=2, mode="bilinear", align_corners=False))
        assert torch.allclose(g(x, torch.tensor(0.0)), up, atol=1e-4)
        assert torch.equal(g(x, torch.tensor(1.0)), g(x))
        mid = g(x, torch.tensor(0.5))
        assert not torch.allclose(mid, g(x)) and not torch.allclose(mid, up)
        pair = torch.cat([x, x], 1)
        for k, (a0, ref) in enumerate(zip(d(pair, torch.tensor(0.0)),
                                          d(F.avg_pool2d(pair, 2)), strict=True)):
            assert torch.allclose(a0[-1], ref[-1], atol=1e-5), k
        for a1, ref in zip(d(pair, torch.tensor(1.0)), d(pair), strict=True):
            assert torch.equal(a1[-1], ref[-1])


def test_test_time_dropout_gives_distinct_reproducible_hypotheses():
    g = StochasticUNet(size=16, channels=8, max_channels=16, min_size=8, dropout=0.5).eval()
    x = torch.rand(1, 1, 16, 16)
    with torch.no_grad():
        assert torch.equal(g(x), g(x))                          # eval: deterministic
        g.stochastic = True
        outs = []
        for seed in (0, 1, 0):
            torch.manual_seed(seed)
            outs.append(g(x))
    assert torch.equal(outs[0], outs[2]) and not torch.equal(outs[0], outs[1])


# ------------------------------------------------------------------------- training
def _record(monkeypatch):
    """Wrap gan_step: record (resolution, alpha value, id of the alpha tensor) per batch."""
    seen = []
    real = TA.gan_step

    def step(g_run, dd_run, dr_run, opt_g, opt_d, x, y, alpha, *args, **kw):
        seen.append((x.shape[-1], None if alpha is None else float(alpha),
                     None if alpha is None else id(alpha)))
        return real(g_run, dd_run, dr_run, opt_g, opt_d, x, y, alpha, *args, **kw)

    monkeypatch.setattr(TA, "gan_step", step)
    return seen


def _weights(path):
    from safetensors.torch import load_file

    return {k: v for k, v in load_file(str(path)).items() if not k.startswith("rng.")}


def test_training_grows_fades_in_one_tensor_and_logs_the_switches(monkeypatch, tmp_path):
    seen = _record(monkeypatch)
    res = TA.train_ab(_pairs(), tmp_path / "run", ABConfig(**TINY), progress=False)
    # 3 batches at 8 px (no fade), then 6 at 16 px: alpha 0, .25, .5, .75, then the new net
    assert [s[0] for s in seen] == [8] * 3 + [16] * 6
    assert [s[1] for s in seen] == [None] * 3 + [0.0, 0.25, 0.5, 0.75, None, None]
    assert len({s[2] for s in seen if s[2] is not None}) == 1    # one tensor, updated in place
    assert [(r["resolution"], r["batch"], r["alpha"], r["fade_batches"])
            for r in res.history] == [(8, 2, 1.0, 0), (16, 2, 0.5, 4), (16, 2, 1.0, 4)]
    run = tmp_path / "run"
    assert (run / "losses.png").is_file() and (run / "samples" / "epoch_0003.png").is_file()
    import json

    from safetensors import safe_open

    with safe_open(str(run / "model.safetensors"), "pt") as f:
        head = json.loads(f.metadata()["map2map"])
    assert head["format"] == "map2map-model-ab" and head["resolution"] == 16
    assert head["alpha"] == 1.0 and head["generator"]["min_size"] == 8
    log = (run / "log.csv").read_text().splitlines()
    assert "resolution" in log[0] and len(log) == 4


def test_resume_mid_fade_continues_at_the_right_resolution_and_alpha(monkeypatch, tmp_path):
    """Ctrl-C in the second batch of the 16 px stage (mid fade-in): the checkpoint says
    epoch 1, batch 2; --resume goes on at 16 px with alpha 0.5 and ends with the weights
    of an uninterrupted run, bit for bit (dropout's random state included)."""
    data = tmp_path / "ds.npz"
    save_packed(data, _pairs())
    TA.train_ab(data, tmp_path / "whole", ABConfig(**TINY), progress=False, figures=False)
    seen = _record(monkeypatch)
    real_step = TA.gan_step

    def step(*args, **kw):
        out = real_step(*args, **kw)
        if len(seen) == 5:                                 # 2nd batch of the 16 px stage
            os.kill(os.getpid(), signal.SIGINT)
        return out

    monkeypatch.setattr(TA, "gan_step", step)
    with pytest.raises(KeyboardInterrupt):
        TA.train_ab(data, tmp_path / "cut", ABConfig(**TINY), progress=False, figures=False)
    from map2map.learn.training.checkpoint import load_checkpoint

    _, state = load_checkpoint(tmp_path / "cut" / "last.safetensors")
    assert (state["epoch"], state["batch"]) == (1, 2)
    seen.clear()
    res = TA.train_ab(data, tmp_path / "cut", resume=True, progress=False, figures=False)
    assert [s[:2] for s in seen] == [(16, 0.5), (16, 0.75), (16, None), (16, None)]
    assert res.epochs_done == 3 and res.history[-1]["resolution"] == 16
    a = _weights(tmp_path / "whole" / "last.safetensors")
    b = _weights(tmp_path / "cut" / "last.safetensors")
    assert a.keys() == b.keys()
    for k in a:
        assert torch.equal(a[k], b[k]), k
    # extending past the schedule stays at its last resolution
    monkeypatch.setattr(TA, "gan_step", real_step)
    res = TA.train_ab(data, tmp_path / "cut", resume=True, epochs=4, progress=False,
                      figures=False)
    assert [r["resolution"] for r in res.history] == [8, 16, 16, 16]


def test_cli_train_ab_and_bad_input(tmp_path, capsys):
    data = tmp_path / "ds"
    data.mkdir()
    save_packed(data / "packed.npz", _pairs())
    run = tmp_path / "run"
    args = ["train", "ab", "--data", str(data), "--out", str(run), "--schedule", "8:1,16:1",
            "--batch", "3", "--g-channels", "8", "--g-max-channels", "16", "--d-channels",
            "8", "--d-layers", "1", "--fade-batches", "1", "--device", "cpu", "--quiet"]
    assert main(args) == 0
    err = capsys.readouterr().err
    assert "trained 2 epochs (now 16 px, alpha 1.00)" in err
    assert (run / "model.safetensors").is_file()
    assert main(args[:-1] + ["--schedule", "8:1,32:1"]) == 2      # not doubling
    assert main(["train", "ab", "--data", str(tmp_path / "none"), "--out",
                 str(tmp_path / "r2")]) == 2
    assert main(args[:4] + ["--out", str(tmp_path / "r3"), "--schedule", "4:1,8:1,16:1"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("map2map: error:") == 3


# ------------------------------------------------------------------------- synthesize
#: synthesize's settings before session 11 (its defaults since: rooms, explore, lidar)
OLD = {"coverage": "none", "traces": "none"}

@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    run = tmp_path_factory.mktemp("ab") / "run"
    n = torch.get_num_threads()
    torch.set_num_threads(1)
    TA.train_ab(_pairs(), run, ABConfig(**{**TINY, "schedule": ((8, 1), (16, 1))}),
                progress=False, figures=False)
    torch.set_num_threads(n)
    return run


def _plan():
    from map2map.core.grid import OccupancyMap

    data = np.full((30, 44), UNKNOWN, np.uint8)
    data[4:26, 6:40] = FREE
    data[4, 6:40] = data[25, 6:40] = OCCUPIED
    data[4:26, 6] = data[4:26, 39] = data[4:26, 20] = OCCUPIED
    return OccupancyMap(data, resolution=0.07, origin=(1.5, -2.0, 0.0))


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_synthesize_keeps_the_plan_frame_and_gives_seeded_distinct_hypotheses(tiny_run):
    from map2map.learn.ab.model import load_ab_model
    from map2map.learn.ab.synthesize import synthesize

    plan = _plan()
    with pytest.warns(UserWarning):
        res = synthesize(plan, tiny_run, samples=3, seed=5)
    assert len(res.maps) == 3
    for m in res.maps:
        assert m.shape == plan.shape and m.resolution == plan.resolution
        assert m.origin == plan.origin
        assert set(np.unique(m.data)) <= {OCCUPIED, UNKNOWN, FREE}
    assert np.all(res.maps[0].data[:, :2] == UNKNOWN)     # outside the plan's square
    again = synthesize(plan, load_ab_model(tiny_run), samples=3, seed=5)
    for a, b in zip(res.maps, again.maps, strict=True):
        assert np.array_equal(a.data, b.data)             # same seed, same maps
    assert res.pairwise.shape == (3, 3) and np.all(np.diag(res.pairwise) == 0)
    assert res.diversity == pytest.approx(res.pairwise[~np.eye(3, dtype=bool)].mean())
    # dropout on: distinct hypotheses (the tiny network draws a few free pixels, which the
    # drift's route coverage may hide: measured without drift)
    assert synthesize(plan, tiny_run, samples=3, seed=5, drift="none").diversity > 0
    one = synthesize(plan, tiny_run, samples=1)
    assert one.diversity == 0.0 and len(one.maps) == 1
    assert any("16 px" in w for w in res.warnings)        # coarse model says so
    from map2map.core.errors import InputError
    from map2map.core.grid import OccupancyMap

    with pytest.raises(InputError, match="no known cells"):
        synthesize(OccupancyMap(np.full((9, 9), UNKNOWN, np.uint8), 0.05), tiny_run)


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_synthesize_render_slam_draws_faces_and_plain_is_the_previous_output(tiny_run):
    from map2map.core.errors import InputError
    from map2map.learn.ab.model import load_ab_model
    from map2map.learn.ab.render import render_plain, render_slam
    from map2map.learn.ab.synthesize import synthesize, synthesize_squares

    net = load_ab_model(tiny_run)
    assert net.wall_px == pytest.approx(net.header["target_wall_px"])
    plan = _plan()
    slam = synthesize(plan, net, samples=2, seed=1)
    plain = synthesize(plan, net, samples=2, seed=1, render="plain")
    assert slam.maps[0].meta["synthesize"]["render"] == "slam"
    plans = _pairs().a[:2]
    grey = net.sample_many(plans, 1, 0)[:, 0]
    S = plans.shape[-1]
    wall = net.wall_px * S / net.data_size
    got = synthesize_squares(net, plans, drift="none")
    assert np.array_equal(got[1], render_slam(grey[1], S, wall).map)
    assert np.array_equal(synthesize_squares(net, plans, render="plain", drift="none")[1],
                          render_plain(grey[1], S))
    for a, b in zip(slam.maps, plain.maps, strict=True):     # same frame, other walls
        assert a.shape == b.shape and a.origin == b.origin
    with pytest.raises(InputError, match="render"):
        synthesize(plan, net, render="blur")


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_synthesize_drift_none_is_the_previous_output_and_parametric_drifts(tiny_run):
    from map2map.learn.ab.drift import DriftParams, apply_drift, drift_field, drift_rng
    from map2map.learn.ab.model import load_ab_model
    from map2map.learn.ab.render import render
    from map2map.learn.ab.synthesize import pairwise_disagreement, synthesize
    from map2map.maps.preprocess import content_square

    net = load_ab_model(tiny_run)
    plan = _plan()
    none = synthesize(plan, net, samples=3, seed=2, drift="none", **OLD)
    # the output before drift existed: rendered squares pasted into the plan's frame,
    # diversity over the square's known pixels
    sq = content_square(plan, net.data_size)
    square, row0, col0, side = sq.data, sq.row0, sq.col0, sq.side
    grey = net.sample(thicken_input(square, net), 3, 2)
    squares = [render(g, side, "slam", net.wall_px * side / net.data_size) for g in grey]
    for k, m in enumerate(none.maps):
        old = np.full(plan.shape, UNKNOWN, np.uint8)
        old[:, :] = squares[k][-row0:-row0 + plan.shape[0], -col0:-col0 + plan.shape[1]]
        assert np.array_equal(m.data, old)
        assert m.meta["synthesize"]["drift"] == "none"
    pw = pairwise_disagreement(np.stack(squares), square != UNKNOWN)
    assert none.diversity == pw[~np.eye(3, dtype=bool)].mean()
    # the tiny network draws nothing: let it draw the plan, so that the drift shows
    net.sample_many = _plan_drawer(net)
    none = synthesize(plan, net, samples=3, seed=2, drift="none", **OLD)
    drift = synthesize(plan, net, samples=3, seed=2, drift="parametric", **OLD)
    again = synthesize(plan, net, samples=3, seed=2, drift=DriftParams(), **OLD)
    for k, (a, b, c) in enumerate(zip(drift.maps, again.maps, none.maps, strict=True)):
        assert np.array_equal(a.data, b.data)                     # same seed, same bytes
        assert np.count_nonzero(c.data == OCCUPIED) > 20
        assert not np.array_equal(a.data, c.data)                 # the drift moved it
        want = apply_drift(c.data, drift_field(plan, drift_rng(2, k)))
        assert np.array_equal(a.data, want)                       # hypothesis k: (seed, k)
        assert a.meta["synthesize"]["drift_params"]["method"] == "additive"
        assert a.meta["synthesize"]["drift_px"]["mean"] > 0
    assert drift.diversity > none.diversity == 0.0                # the drift differs
    ekf = synthesize(plan, net, samples=1, seed=2, drift="parametric", drift_method="ekf",
                     **OLD)
    assert ekf.maps[0].meta["synthesize"]["drift_params"]["method"] == "ekf"
    from map2map.core.errors import InputError

    with pytest.raises(InputError, match="drift"):
        synthesize(plan, net, drift="rigid")


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_synthesize_rooms_drift_is_seeded_and_leaves_the_other_choices_alone(tiny_run):
    from map2map.learn.ab.drift import apply_drift, drift_field, drift_rng
    from map2map.learn.ab.model import load_ab_model
    from map2map.learn.ab.room_drift import RoomDriftParams
    from map2map.learn.ab.synthesize import synthesize, synthesize_squares

    net = load_ab_model(tiny_run)
    net.sample_many = _plan_drawer(net)
    plan = _plan()
    none = synthesize(plan, net, samples=2, seed=2, drift="none", **OLD)
    rooms = synthesize(plan, net, samples=2, seed=2, drift="rooms", **OLD)
    again = synthesize(plan, net, samples=2, seed=2, drift=RoomDriftParams(), **OLD)
    for k, (a, b, c) in enumerate(zip(rooms.maps, again.maps, none.maps, strict=True)):
        assert a.data.tobytes() == b.data.tobytes()              # same seed, same bytes
        want = apply_drift(c.data, drift_field(plan, drift_rng(2, k), RoomDriftParams()))
        assert np.array_equal(a.data, want)                       # hypothesis k: (seed, k)
        assert a.meta["synthesize"]["drift"] == "rooms"
        assert a.meta["synthesize"]["drift_params"]["rot_deg"] == RoomDriftParams().rot_deg
    plans = _pairs(n=2, size=32, seed=4).a
    sq = synthesize_squares(net, plans, seed=1, drift="rooms")
    assert np.array_equal(sq, synthesize_squares(net, plans, seed=1, drift="rooms"))


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_synthesize_lidar_traces_are_seeded_metric_and_leave_traces_none_alone(tiny_run):
    from map2map.core.errors import InputError
    from map2map.learn.ab.model import load_ab_model
    from map2map.learn.ab.render import TraceParams, band_px
    from map2map.learn.ab.synthesize import synthesize, synthesize_squares

    net = load_ab_model(tiny_run)
    net.sample_many = _plan_drawer(net)
    plan = _plan()
    base = synthesize(plan, net, samples=2, seed=2, drift="none", **OLD)
    tr = synthesize(plan, net, samples=2, seed=2, drift="none", coverage="none",
                    traces="lidar")
    again = synthesize(plan, net, samples=2, seed=2, drift="none", coverage="none",
                       traces=TraceParams())
    auto = synthesize(plan, net, samples=2, seed=2, drift="none", coverage="none")
    for a, b, c, d in zip(tr.maps, again.maps, base.maps, auto.maps, strict=True):
        assert a.data.tobytes() == b.data.tobytes() == d.data.tobytes()  # lidar: default
        assert a.data.tobytes() != c.data.tobytes()              # traces drawn
        assert "traces" not in c.meta["synthesize"]              # traces none: as before
        assert a.meta["synthesize"]["traces"]["wall_m"] == TraceParams().wall_m
    assert tr.maps[0].data.tobytes() != tr.maps[1].data.tobytes()   # own stream per k
    with pytest.raises(InputError):
        synthesize(plan, net, samples=1, render="plain", traces="lidar")
    plans = _pairs(n=2, size=32, seed=4).a
    sq = synthesize_squares(net, plans, seed=1, drift="none", traces="lidar",
                            resolution=[0.03, 0.12])
    assert np.array_equal(sq, synthesize_squares(net, plans, seed=1, drift="none",
                                                 traces="lidar", resolution=[0.03, 0.12]))
    assert band_px(0.03, TraceParams()) > 1.5 * band_px(0.12, TraceParams())
    # no strays, no rough edge, no inset: the band alone, thicker on the finer square
    from map2map.learn.ab.model import ABModel
    from map2map.learn.nets.progressive import StochasticUNet

    sq = np.full((64, 64), UNKNOWN, np.uint8)
    sq[4:60, 4:60] = OCCUPIED
    sq[12:52, 12:28] = sq[12:52, 36:52] = FREE           # walls 8 px thick
    wide = ABModel(StochasticUNet(size=32, channels=8, min_size=16), resolution=32,
                   alpha=1.0, data_size=64, header={"target_wall_px": 2.0}, source="test")
    wide.sample_many = _plan_drawer(wide)
    flat = TraceParams(rough_px=0.0, strays=0.0, wall_m=0.06, inset_px=0.0)
    one = synthesize_squares(wide, np.stack([sq] * 2), seed=1, drift="none", traces=flat,
                             resolution=[0.02, 0.2])
    n_fine, n_coarse = (np.count_nonzero(o == OCCUPIED) for o in one)
    assert n_fine > 2.5 * n_coarse > 0                   # 4.2 px against 1.5 px bands


def _plan_drawer(net):
    """A stand-in for ``net.sample_many``: the input plans reduced to the output size,
    the same for every sample."""
    from map2map.learn.training.data import reduce_input

    def sample_many(inputs, samples=1, seed=0):
        x = reduce_input(np.asarray(inputs, np.uint8), net.resolution, "area")
        return np.repeat(x[:, None].astype(np.float32), samples, axis=1)

    return sample_many


def thicken_input(square, net):
    from map2map.learn.ab.synthesize import dataset_thicken
    from map2map.maps.preprocess import square_resize, thicken

    return thicken(square_resize(square, net.data_size), dataset_thicken(net.header))


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_synthesize_squares_drifts_each_plan_at_its_resolution(tiny_run):
    from map2map.learn.ab.drift import DriftParams, drift_maps
    from map2map.learn.ab.model import load_ab_model
    from map2map.learn.ab.synthesize import synthesize_squares

    net = load_ab_model(tiny_run)
    net.sample_many = _plan_drawer(net)                 # draws the plan (tiny net: nothing)
    plans = _pairs(n=3, size=32, seed=4).a
    none = synthesize_squares(net, plans, drift="none")
    got = synthesize_squares(net, plans, seed=1, resolution=[0.06, 0.07, 0.08])
    assert np.array_equal(got, synthesize_squares(net, plans, seed=1,
                                                  resolution=[0.06, 0.07, 0.08]))
    assert all(not np.array_equal(g, n) for g, n in zip(got, none, strict=True))
    want, _ = drift_maps(none, plans, [0.06, 0.07, 0.08], 1, DriftParams())
    assert np.array_equal(got, want)                   # plan i: drift_rng(seed, i)
    assert not np.array_equal(got, synthesize_squares(net, plans, seed=1, resolution=0.06,
                                                      drift_scale=3.0))


@pytest.mark.parametrize("cells", [2, 4])
def test_synthesize_at_two_px_per_cell_draws_target_walls_without_the_coarse_warning(cells):
    """A model trained to half the data square (a 128 px model of 256 px pairs: one output
    cell is 2 px, the simulated walls' thickness) draws its walls ``target_wall_px`` thick
    and is not called coarse; at 4 px a cell (the 64 px models) the warning stays."""
    from map2map.core.grid import OccupancyMap
    from map2map.learn.ab.model import ABModel
    from map2map.learn.ab.synthesize import synthesize
    from map2map.maps.preprocess import wall_thickness_px

    S = 64
    data = np.full((S, S), UNKNOWN, np.uint8)
    data[4:60, 4:60] = OCCUPIED                   # building: outer walls 4 px thick, the
    data[8:56, 8:28] = data[8:56, 36:56] = FREE   # inner one 8 px; the square is the plan
    plan = OccupancyMap(data, resolution=0.05)
    r = S // cells
    net = ABModel(StochasticUNet(size=r, channels=8, min_size=r // 2), resolution=r,
                  alpha=1.0, data_size=S, header={"target_wall_px": 2.0}, source="test")
    net.sample_many = _plan_drawer(net)           # draws the plan at r px
    with pytest.warns(UserWarning) if cells > 2 else _no_warning():
        res = synthesize(plan, net, samples=1, drift="none", **OLD)
    coarse = [w for w in res.warnings if "one output cell is" in w]
    assert len(coarse) == (cells > 2)
    if cells > 2:
        assert f"{cells:.1f} plan pixels" in coarse[0]
    m = res.maps[0].data
    assert wall_thickness_px(m[None]) == pytest.approx(2.0, abs=0.35)
    if cells == 2:                                # faces 2 px, the wall's inside unseen
        assert np.all(m[20:44, 28:30] == OCCUPIED) and np.all(m[20:44, 34:36] == OCCUPIED)
        assert np.all(m[20:44, 30:34] == UNKNOWN)
        assert np.all(m[20:44, 4:6] == UNKNOWN) and np.all(m[20:44, 6:8] == OCCUPIED)


def _no_warning():
    import warnings
    from contextlib import contextmanager

    @contextmanager
    def ctx():
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            yield

    return ctx()


def test_cli_synthesize_writes_maps_summary_and_figure(tiny_run, tmp_path, capsys):
    import json

    from map2map.maps.formats import load_map, save_map

    save_map(_plan(), tmp_path / "plan.yaml")
    out = tmp_path / "hyps"
    # the tiny network draws next to nothing; without drift a hypothesis still reads back
    rc = main(["synthesize", str(tmp_path / "plan.yaml"), "--out", str(out), "--samples", "3",
               "--model", str(tiny_run), "--drift", "none", "--coverage", "none"])
    assert rc == 0
    m = load_map(out / "plan_hyp02.yaml")
    assert m.shape == (30, 44) and m.resolution == pytest.approx(0.07)
    assert m.origin[:2] == pytest.approx((1.5, -2.0))
    summary = json.loads((out / "plan_synthesize.json").read_text())
    assert summary["samples"] == 3 and 0 < summary["diversity_mean_pairwise_disagreement"] < 1
    assert (out / "plan_synthesize.png").stat().st_size > 1000
    assert summary["render"] == "slam" and summary["drift"] == "none"
    assert "coverage" not in summary and summary["traces"]["inset_px"] == 1.0   # lidar
    assert main(["synthesize", str(tmp_path / "plan.yaml"), "--out", str(tmp_path / "p"),
                 "--samples", "2", "--format", "png", "--no-figure", "--model",
                 str(tiny_run), "--render", "plain", "--drift", "parametric"]) == 0
    p = json.loads((tmp_path / "p" / "plan_synthesize.json").read_text())
    assert p["drift"] == "parametric" and p["drift_params"]["method"] == "additive"
    assert "traces" not in p                         # plain: no LIDAR traces by default
    assert main(["synthesize", str(tmp_path / "plan.yaml"), "--out", str(tmp_path / "e"),
                 "--samples", "1", "--no-figure", "--model", str(tiny_run),
                 "--drift", "parametric", "--drift-method", "ekf", "--drift-scale", "0.5"]) == 0
    e = json.loads((tmp_path / "e" / "plan_synthesize.json").read_text())
    assert (e["drift_params"]["method"], e["drift_params"]["scale"]) == ("ekf", 0.5)
    assert main(["synthesize", str(tmp_path / "plan.yaml"), "--out", str(tmp_path / "r"),
                 "--samples", "1", "--no-figure", "--model", str(tiny_run),
                 "--drift", "rooms", "--drift-scale", "0.5"]) == 0
    r = json.loads((tmp_path / "r" / "plan_synthesize.json").read_text())
    assert r["drift"] == "rooms" and r["drift_params"]["scale"] == 0.5
    assert r["coverage"] == "explore" and "traces" in r     # the defaults since session 11
    assert sorted(p.name for p in (tmp_path / "p").iterdir()) == \
        ["plan_hyp00.png", "plan_hyp01.png", "plan_synthesize.json"]
    err = capsys.readouterr().err
    assert "mean pairwise disagreement" in err
    from map2map.learn.ba.model import pretrained_path

    bad = [["--samples", "0"], ["--model", str(pretrained_path())],
           ["--model", str(tmp_path / "nope")], ["--drift-scale", "-1"]]
    for extra in bad:
        assert main(["synthesize", str(tmp_path / "plan.yaml"), "--out",
                     str(tmp_path / "bad"), *extra]) == 2
    assert main(["synthesize", str(tmp_path / "none.yaml"), "--out", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("map2map: error:") == 5
    assert not (tmp_path / "bad").exists()


@pytest.mark.slow
def test_ddp_two_processes_gloo(tmp_path):
    """torchrun with 2 CPU processes (gloo) through a stage switch: one run folder, one
    report, a loadable model at the last resolution (unused finer blocks do not stall DDP)."""
    import subprocess
    import sys
    from pathlib import Path

    data = tmp_path / "ds.npz"
    save_packed(data, _pairs(10))
    src = str(Path(__file__).resolve().parents[1] / "src")
    env = {**os.environ, "OMP_NUM_THREADS": "1",
           "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")])}
    cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone",
           "--nproc_per_node", "2", "-m", "map2map", "train", "ab", "--data", str(data),
           "--out", str(tmp_path / "run"), "--schedule", "8:1,16:1", "--batch", "4",
           "--g-channels", "8", "--g-max-channels", "16", "--d-channels", "8",
           "--d-layers", "1", "--fade-batches", "1", "--device", "cpu", "--quiet"]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=240)
    # a rank that fails is reported at the end by torchrun; its own error is further up
    cause = [ln for ln in out.stderr.splitlines() if any(
        w in ln for w in ("Error", "error:", "terminate", "Traceback", "Signal", "abort",
                          "trained"))]
    assert out.returncode == 0, "\n".join(cause[:40]) + "\n...\n" + out.stderr[-1500:]
    assert out.stderr.count("trained 2 epochs") == 1
    from map2map.learn.ab.model import load_ab_model

    assert load_ab_model(tmp_path / "run").resolution == 16


def test_pretrained_weights_load_and_synthesize():
    from map2map.learn.ab.model import load_ab_model, pretrained_ab_path
    from map2map.learn.ab.synthesize import synthesize

    path = pretrained_ab_path()
    assert path.is_file() and path.stat().st_size <= 10 * 2**20
    net = load_ab_model("pretrained")
    assert "PROVISIONAL" in net.header["note"]
    assert net.header["format"] == "map2map-model-ab" and net.resolution >= 16
    plan = _plan()
    with pytest.warns(UserWarning, match="provisional"):
        res = synthesize(plan, "pretrained", samples=2, seed=1)
    assert [m.shape for m in res.maps] == [plan.shape] * 2


# ------------------------------------------------------------------ decoder-only growth
def test_decoder_growth_shapes_at_each_stage_and_fade_end_points():
    """growth="decoder" (anime2clothing's): the generator always reads the last stage's
    size, its output is the stage's; alpha 0 is the upsampled previous exit, alpha 1 the
    new one; the discriminators are the full growth's."""
    torch.manual_seed(0)
    cfg = ABConfig(schedule=((8, 1), (16, 1), (32, 1)), g_channels=8, g_max_channels=16,
                   d_channels=8, d_layers=1, d_scales=2, growth="decoder", dropout=0.0)
    g, dd, dr = build_ab_networks(cfg)
    g.eval()
    x = torch.rand(2, 1, 32, 32) * 2 - 1
    for r in (8, 16, 32):
        g.out_size = r
        for alpha in (None, torch.tensor(0.3)):
            y = g(x, alpha)
            assert y.shape == (2, 1, r, r)
            xr = F.adaptive_avg_pool2d(x, r)
            assert [o[-1].shape[-1] for o in dd(torch.cat([xr, y], 1), alpha)] == [4, 2]
    with pytest.raises(ValueError):
        g(torch.zeros(1, 1, 16, 16))                        # not the full-size input
    with torch.no_grad():
        g.out_size = 8
        coarse = g(x)
        g.out_size = 16
        up = torch.tanh(F.interpolate(torch.atanh(coarse.clamp(-0.999999, 0.999999)),
                                      scale_factor=2, mode="bilinear", align_corners=False))
        assert torch.allclose(g(x, torch.tensor(0.0)), up, atol=1e-4)
        assert torch.equal(g(x, torch.tensor(1.0)), g(x))
    with pytest.raises(ValueError):
        ABConfig(growth="encoder")


def test_decoder_growth_trains_feeds_full_size_inputs_and_loads(monkeypatch, tmp_path):
    inputs = []
    real = TA.gan_step

    def step(*args, **kw):
        g_input = args[12] if len(args) > 12 else kw.get("g_input")
        inputs.append((args[5].shape[-1], args[6].shape[-1], g_input.shape[-1]))
        return real(*args, **kw)

    monkeypatch.setattr(TA, "gan_step", step)
    res = TA.train_ab(_pairs(), tmp_path / "run", ABConfig(**TINY, growth="decoder"),
                      progress=False, figures=False)
    # D_d's input and the target at the stage's size, the generator's input always 16 px
    assert inputs == [(8, 8, 16)] * 3 + [(16, 16, 16)] * 6
    assert [r["resolution"] for r in res.history] == [8, 16, 16]
    from map2map.learn.ab.model import load_ab_model
    from map2map.learn.ab.synthesize import synthesize_squares

    net = load_ab_model(tmp_path / "run")
    assert net.generator.growth == "decoder" and net.resolution == 16
    out = synthesize_squares(net, _pairs().a[:3])
    assert out.shape == (3, 16, 16) and set(np.unique(out)) <= {OCCUPIED, UNKNOWN, FREE}


@pytest.mark.parametrize("header", [{"dataset": {"thicken": 1}},
                                    {"dataset": {"identity": {"params": {"thicken": 1}}}}])
def test_synthesize_thickens_the_plan_as_the_training_dataset_did(header):
    """A dataset build records ``thicken`` under ``identity.params`` (packed pairs too):
    the shipped weights' header. synthesize read only ``dataset.thicken`` and fed those
    models plans 1 px thinner a side than they were trained on (fixed session 14)."""
    from map2map.core.grid import OccupancyMap
    from map2map.learn.ab.model import ABModel
    from map2map.learn.ab.synthesize import synthesize

    S = 64
    data = np.full((S, S), UNKNOWN, np.uint8)
    data[4:60, 4:60] = OCCUPIED
    data[6:58, 6:30] = data[6:58, 32:58] = FREE          # a 2 px dividing wall
    plan = OccupancyMap(data, resolution=0.05)
    net = ABModel(StochasticUNet(size=16, channels=8, min_size=8), resolution=16,
                  alpha=1.0, data_size=S, header={"target_wall_px": 2.0, **header},
                  source="test")
    seen = []

    def sample(inp, samples=1, seed=0):
        seen.append(np.asarray(inp).copy())
        return np.full((samples, 16, 16), 255.0, np.float32)

    net.sample = sample
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        synthesize(plan, net, samples=1, drift="none", **OLD)
    (inp,) = seen
    row = inp[inp.shape[0] // 2]
    walls = np.flatnonzero(row == OCCUPIED)
    mid = walls[(walls > 10) & (walls < 54)]
    assert len(mid) == 4                              # the 2 px wall, 1 px more a side
