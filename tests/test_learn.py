"""Model_BA: losses against hand computations, discriminator pairing, exact resume,
safetensors without pickle, autocorrect's frame handling, the command lines."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("safetensors")

from map2map.cli.main import main  # noqa: E402
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap  # noqa: E402
from map2map.datasets.packed import PackedPairs, save_packed  # noqa: E402
from map2map.learn.ba import train as T  # noqa: E402
from map2map.learn.ba.autocorrect import autocorrect_many  # noqa: E402
from map2map.learn.ba.model import BAModel, load_model  # noqa: E402
from map2map.learn.nets import losses as L  # noqa: E402
from map2map.learn.training.config import TrainConfig  # noqa: E402
from map2map.learn.training.data import downsample_target  # noqa: E402

pytestmark = pytest.mark.usefixtures("one_torch_thread")


TINY = dict(size=16, epochs=2, batch=4, g_channels=8, g_max_channels=16, d_channels=8,
            d_layers=2, samples=2)


def _pairs(n=10, size=32, seed=0) -> PackedPairs:
    """Boxes with a wall (A) and a shifted, speckled copy (B)."""
    rng = np.random.default_rng(seed)
    a = np.full((n, size, size), UNKNOWN, np.uint8)
    for i in range(n):
        r0, c0 = rng.integers(2, 8, 2)
        a[i, r0:size - 3, c0:size - 3] = FREE
        a[i, r0, c0:size - 3] = OCCUPIED
        a[i, size - 4, c0:size - 3] = OCCUPIED
        a[i, r0:size - 3, rng.integers(c0 + 3, size - 5)] = OCCUPIED
    b = np.roll(a, 1, axis=2)
    b[rng.random(b.shape) < 0.03] = UNKNOWN
    split = np.array(["train"] * (n - 2) + ["val", "test"])
    return PackedPairs(a, b, np.array([f"p{i}" for i in range(n)]), split, {"seed": seed})


# ----------------------------------------------------------------------------- losses
def _scales(*arrays):
    return [[torch.tensor(a, dtype=torch.float32).reshape(1, 1, 1, -1) for a in feats]
            for feats in arrays]


def test_gan_losses_match_hand_computation():
    real = _scales([[2.0, -1.0]])              # logits
    fake = _scales([[0.5, -3.0]])
    false = _scales([[1.0, 0.0]])
    sp = lambda z: math.log1p(math.exp(z))   # -log sigmoid(-z) = softplus(z)  # noqa: E731
    d_real = (sp(-2.0) + sp(1.0)) / 2          # -log D(real)
    d_fake = (sp(0.5) + sp(-3.0)) / 2          # -log(1 - D(fake))
    d_false = (sp(1.0) + sp(0.0)) / 2
    got = float(L.gan_real_fake_3_4(real, fake, side="d"))
    assert got == pytest.approx(d_real + d_fake, rel=1e-6)
    got = float(L.gan_domain_3_3(real, fake, false, side="d"))
    assert got == pytest.approx(d_real + 0.5 * (d_fake + d_false), rel=1e-6)
    g = (sp(-0.5) + sp(3.0)) / 2               # -log D(fake), non-saturating
    assert float(L.gan_domain_3_3(None, fake, side="g")) == pytest.approx(g, rel=1e-6)
    assert float(L.gan_real_fake_3_4(None, fake, side="g")) == pytest.approx(g, rel=1e-6)
    # three scales are summed (eq. 3.2's sum over k)
    three = real * 3
    assert float(L.gan_real_fake_3_4(three, fake * 3, side="d")) == pytest.approx(
        3 * (d_real + d_fake), rel=1e-6)


def test_feature_terms_match_hand_computation():
    # two intermediate layers (2 and 4 elements) + logits, two scales
    a = [[torch.tensor([1.0, 2.0]), torch.tensor([0.0, 0.0, 0.0, 4.0]), torch.tensor([9.0])]] * 2
    b = [[torch.tensor([2.0, 0.0]), torch.tensor([1.0, 1.0, 1.0, 1.0]), torch.tensor([-9.0])]] * 2
    per_scale = (1 + 2) / 2 + (1 + 1 + 1 + 3) / 4   # mean |diff| per layer, logits left out
    assert float(L.feature_matching_3_5(a, b)) == pytest.approx(2 * per_scale)
    assert float(L.input_consistency_3_6(a, b)) == pytest.approx(2 * per_scale)
    x = torch.tensor([[0.0, 1.0], [-1.0, 0.5]])
    y = torch.tensor([[1.0, 1.0], [1.0, 0.0]])
    assert float(L.l1_3_7(x, y)) == pytest.approx((1 + 0 + 2 + 0.5) / 4)


def test_generator_loss_sums_its_terms_and_real_side_gets_no_gradient():
    real = [[torch.ones(1, 2, 2, 2), torch.zeros(1, 1, 1, 1)]]
    feat = torch.zeros(1, 2, 2, 2, requires_grad=True)
    fake = [[feat, torch.zeros(1, 1, 1, 1, requires_grad=True)]]
    total, terms = L.generator_loss_3_2(real, fake, real, fake, torch.zeros(3),
                                        torch.ones(3), lambda_l1=10.0)
    expect = (terms["gan_domain_3_3"] + terms["gan_real_fake_3_4"] + terms["fm_3_5"]
              + terms["ic_3_6"] + 10.0 * terms["l1_3_7"])
    assert float(total.detach()) == pytest.approx(float(expect.detach()))
    total.backward()
    assert feat.grad is not None and real[0][0].grad is None


# ------------------------------------------------------------------------- training
def test_discriminator_pairing(monkeypatch, tmp_path):
    """D_d: (x, y) real, (x, G(x)) fake, (x, y') false target of another input; D_r: y, G(x)."""
    seen = {"dd": [], "dr": [], "g": []}
    real_build = T.build_networks

    def build(cfg):
        g, dd, dr = real_build(cfg)
        g.register_forward_hook(lambda m, i, o: seen["g"].append((i[0].clone(), o.detach())))
        dd.register_forward_pre_hook(lambda m, i: seen["dd"].append(i[0].detach().clone()))
        dr.register_forward_pre_hook(lambda m, i: seen["dr"].append(i[0].detach().clone()))
        return g, dd, dr

    monkeypatch.setattr(T, "build_networks", build)
    cfg = TrainConfig(**{**TINY, "epochs": 1, "samples": 0})
    T.train_ba(_pairs(), tmp_path / "run", cfg, progress=False, figures=False)
    x, fake = seen["g"][0]
    B = len(x)
    dd = seen["dd"][0]                         # the first discriminator step
    assert dd.shape[0] == 3 * B and dd.shape[1] == 2
    real_pair, fake_pair, false_pair = dd[:B], dd[B:2 * B], dd[2 * B:]
    y = real_pair[:, 1:]
    for pair in (real_pair, fake_pair, false_pair):
        assert torch.equal(pair[:, :1], x)         # every pair starts with the input
    assert torch.equal(fake_pair[:, 1:], fake)
    false_y = false_pair[:, 1:]
    # each false target is the target of another input of the batch, untransformed
    for i in range(B):
        assert not torch.equal(false_y[i], y[i])
        assert any(torch.equal(false_y[i], y[j]) for j in range(B) if j != i)
    dr = seen["dr"][0]
    assert torch.equal(dr[:B], y) and torch.equal(dr[B:], fake)


def _weights(path):
    from safetensors.torch import load_file

    return load_file(str(path))


def test_save_every_saves_less_and_trains_the_same(tmp_path):
    """--save-every 2 of 3 epochs: samples and checkpoints at epochs 2 and 3 only, the
    same weights and losses as saving every epoch."""
    data = tmp_path / "ds.npz"
    save_packed(data, _pairs())
    T.train_ba(data, tmp_path / "each", TrainConfig(**{**TINY, "epochs": 3}), progress=False)
    T.train_ba(data, tmp_path / "two", TrainConfig(**{**TINY, "epochs": 3, "save_every": 2}),
               progress=False)
    shots = sorted(p.name for p in (tmp_path / "two" / "samples").iterdir())
    assert shots == ["epoch_0002.png", "epoch_0003.png"]
    a = _weights(tmp_path / "each" / "last.safetensors")
    b = _weights(tmp_path / "two" / "last.safetensors")
    assert all(torch.equal(a[k], b[k]) for k in a)
    import csv

    def losses(run):  # the timing columns differ, the losses may not
        rows = csv.DictReader((tmp_path / run / "log.csv").read_text().splitlines())
        return [{k: v for k, v in r.items() if k not in ("epoch_s", "img_per_s")} for r in rows]

    assert losses("each") == losses("two") and len(losses("two")) == 3


def test_resume_continues_exactly(tmp_path):
    data = tmp_path / "ds.npz"
    save_packed(data, _pairs())
    cfg = TrainConfig(**TINY)
    T.train_ba(data, tmp_path / "two", cfg, progress=False)
    T.train_ba(data, tmp_path / "split", TrainConfig(**{**TINY, "epochs": 1}), progress=False,
               figures=False)
    res = T.train_ba(data, tmp_path / "split", resume=True, epochs=2, progress=False,
                     figures=False)
    assert res.epochs_done == 2 and len(res.history) == 2
    a = _weights(tmp_path / "two" / "last.safetensors")
    b = _weights(tmp_path / "split" / "last.safetensors")
    assert a.keys() == b.keys()
    for k in a:
        assert torch.equal(a[k], b[k]), k
    log = (tmp_path / "split" / "log.csv").read_text().splitlines()
    assert len(log) == 3 and log[0].startswith("epoch,lr,")
    assert (tmp_path / "two" / "samples" / "epoch_0002.png").is_file()
    # a finished run refuses to be overwritten; a wrong dataset refuses to resume
    from map2map.core.errors import InputError

    with pytest.raises(InputError, match="already holds a checkpoint"):
        T.train_ba(data, tmp_path / "two", cfg, progress=False)
    other = tmp_path / "other.npz"
    save_packed(other, _pairs(seed=1))
    with pytest.raises(InputError, match="digest"):
        T.train_ba(other, tmp_path / "two", resume=True, progress=False)


def test_checkpoints_are_safetensors_without_pickle(tmp_path, monkeypatch):
    run = tmp_path / "run"
    T.train_ba(_pairs(), run, TrainConfig(**{**TINY, "epochs": 1}), progress=False,
               figures=False)
    for name in ("last.safetensors", "model.safetensors"):
        raw = (run / name).read_bytes()
        n = int.from_bytes(raw[:8], "little")
        assert raw[8:9] == b"{" and raw[8 + n - 1:8 + n].strip() in (b"}", b"")
        assert b"\x80\x04" not in raw[:16]           # no pickle protocol header

    def no_pickle(*a, **k):
        raise AssertionError("torch.load (pickle) must not be used")

    monkeypatch.setattr(torch, "load", no_pickle)
    model = load_model(run)
    assert model.size == 16 and model.header["dataset"]["digest"]
    res = T.train_ba(_pairs(), run, resume=True, epochs=2, progress=False, figures=False)
    assert res.epochs_done == 2


# ----------------------------------------------------------------------- autocorrect
class _Identity(BAModel):
    """A stand-in generator that returns its input, reduced with walls kept: isolates the
    frame handling from what a network learnt."""

    def __init__(self, size=32, data_size=256):
        super().__init__(None, size, data_size, 3.0, {}, "identity")

    def predict(self, inputs, batch=256):
        return downsample_target(inputs, self.size).astype(np.float32)


def test_autocorrect_keeps_frame_resolution_and_world_positions():
    h, w = 150, 230
    data = np.full((h, w), UNKNOWN, np.uint8)
    data[30:130, 20:200] = FREE
    data[30, 20:200] = OCCUPIED                   # walls
    data[129, 20:200] = OCCUPIED
    data[30:130, 20] = OCCUPIED
    data[30:130, 199] = OCCUPIED
    data[30:130, 111] = OCCUPIED                  # an inner wall
    m = OccupancyMap(data, 0.037, (3.5, -1.25, 0.3))
    (res,) = autocorrect_many([m], _Identity())
    out = res.map
    assert out.shape == m.shape and out.resolution == m.resolution and out.origin == m.origin
    assert set(np.unique(out.data).tolist()) <= {OCCUPIED, UNKNOWN, FREE}
    # the inner wall comes back in the same column (within 2 px), whole and straight
    cols = np.flatnonzero((out.data[40:120] == OCCUPIED).mean(axis=0) > 0.9)
    assert any(abs(c - 111) <= 2 for c in cols)
    assert (out.data[:20] == UNKNOWN).all()       # outside the content stays unknown
    # segments are in world metres (the map's yaw applied): the inner wall's ends map back
    # onto column 111 of the input
    seg = res.segments
    r0, c0 = m.world_to_pixel_float(seg[:, 0], seg[:, 1])
    r1, c1 = m.world_to_pixel_float(seg[:, 2], seg[:, 3])
    inner = (np.abs(c0 - 111) <= 1.5) & (np.abs(c1 - 111) <= 1.5)
    assert inner.any() and np.abs(r1[inner] - r0[inner]).max() > 90
    assert res.warnings == [] and 0.9 <= out.meta["autocorrect"]["support"] <= 1.0


def test_autocorrect_handles_small_and_empty_maps():
    empty = OccupancyMap(np.full((20, 30), UNKNOWN, np.uint8), 0.05)
    small = np.full((12, 9), FREE, np.uint8)
    small[0] = OCCUPIED
    r_empty, r_small = autocorrect_many([empty, OccupancyMap(small, 0.05)], _Identity())
    assert r_empty.map == empty and r_empty.warnings
    assert r_small.map.shape == (12, 9)


def test_pretrained_weights_load_and_run():
    model = load_model("pretrained")
    assert model.header["format"] == "map2map-model-ba"
    assert model.generator.to_map[str(model.size)].weight.dtype == torch.float32
    from map2map.learn.ba.model import pretrained_path

    assert pretrained_path().stat().st_size <= 10 * 2**20


# --------------------------------------------------------------------------- CLI
def test_cli_train_and_autocorrect(tmp_path, capsys):
    data = tmp_path / "ds"
    data.mkdir()
    save_packed(data / "packed.npz", _pairs())
    run = tmp_path / "run"
    rc = main(["train", "ba", "--data", str(data), "--out", str(run), "--epochs", "1",
               "--size", "16", "--batch", "4", "--g-channels", "8", "--d-channels", "8",
               "--d-layers", "2",
               "--quiet"])
    assert rc == 0 and (run / "losses.png").is_file()
    from map2map.maps.formats import load_map, save_map

    m = OccupancyMap(_pairs().b[0], 0.05, (1.0, 2.0, 0.0))
    maps = tmp_path / "maps"
    maps.mkdir()
    save_map(m, maps / "a.yaml")
    save_map(m, maps / "b.png")
    rc = main(["autocorrect", str(maps / "a.yaml"), "--out", str(tmp_path / "cad.yaml"),
               "--model", str(run), "--dxf", str(tmp_path / "w.dxf"),
               "--figure", str(tmp_path / "fig.png")])
    assert rc == 0
    back = load_map(tmp_path / "cad.yaml")
    assert back.shape == m.shape and back.origin == m.origin and back.resolution == m.resolution
    assert (tmp_path / "w.dxf").is_file() and (tmp_path / "fig.png").is_file()
    rc = main(["autocorrect", str(maps), "--out", str(tmp_path / "outdir"), "--model", str(run)])
    assert rc == 0 and sorted(p.name for p in (tmp_path / "outdir").iterdir()) == [
        "a.pgm", "a.yaml", "b.png"]
    capsys.readouterr()
    assert main(["autocorrect", str(tmp_path / "nope.yaml"), "--out",
                 str(tmp_path / "x.yaml")]) == 2
    assert main(["autocorrect", str(maps / "a.yaml"), "--out", str(tmp_path / "x.yaml"),
                 "--model", str(tmp_path)]) == 2
    assert main(["train", "ba", "--data", str(tmp_path / "none"), "--out", str(run)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("map2map: error:") == 3


def test_cli_train_on_two_builds_merges_them_and_names_both(tmp_path, capsys):
    """``--data DS1 DS2``: one run on both builds' pairs (their splits kept, plan ids kept
    apart), both named in the model's header; resume needs the same list; a build of
    another map size is refused by name."""
    from safetensors import safe_open

    def read_header(path):
        with safe_open(str(path), framework="pt") as f:
            return json.loads(f.metadata()["map2map"])

    d1, d2 = tmp_path / "d1.npz", tmp_path / "d2.npz"
    save_packed(d1, _pairs(6, seed=0))
    save_packed(d2, _pairs(4, seed=1))
    run = tmp_path / "run"
    opts = ["--size", "16", "--batch", "4", "--g-channels", "8", "--d-channels", "8",
            "--d-layers", "2", "--quiet"]
    assert main(["train", "ba", "--data", str(d1), str(d2), "--out", str(run), "--epochs",
                 "1", *opts]) == 0
    merged = read_header(run / "model.safetensors")["dataset"]["merged"]
    assert [m["source"] for m in merged] == [str(d1), str(d2)]
    assert [m["count"] for m in merged] == [6, 4]
    assert main(["train", "ba", "--data", str(d1), str(d2), "--out", str(run), "--epochs",
                 "2", "--resume", "--quiet"]) == 0
    capsys.readouterr()
    assert main(["train", "ba", "--data", str(d1), "--out", str(run), "--epochs", "3",
                 "--resume", "--quiet"]) == 2
    save_packed(tmp_path / "big.npz", _pairs(2, size=64))
    assert main(["train", "ba", "--data", str(d1), str(tmp_path / "big.npz"), "--out",
                 str(tmp_path / "r2"), "--epochs", "1", *opts]) == 2
    err = capsys.readouterr().err
    assert "digest differs" in err and "big.npz" in err and "Traceback" not in err


@pytest.mark.slow
def test_ddp_two_processes_gloo(tmp_path):
    """torchrun with 2 CPU processes (gloo): one run folder, one report, a loadable model."""
    data = tmp_path / "ds.npz"
    save_packed(data, _pairs(18))
    import os

    src = str(Path(__file__).resolve().parents[1] / "src")
    env = {**os.environ, "OMP_NUM_THREADS": "1",
           "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")])}
    cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone",
           "--nproc_per_node", "2", "-m", "map2map", "train", "ba", "--data", str(data),
           "--out", str(tmp_path / "run"), "--epochs", "1", "--size", "16", "--batch", "4",
           "--g-channels", "8", "--d-channels", "8", "--d-layers", "2", "--device", "cpu",
           "--quiet"]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=240)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stderr.count("trained 1 epochs") == 1
    assert load_model(tmp_path / "run").size == 16


def test_train_runs_without_shapely(tmp_path):
    """The GPU machines have torch but no shapely: ``map2map train`` must not need it
    (building the parser once imported the DXF reader for its unit names)."""
    data = tmp_path / "ds.npz"
    save_packed(data, _pairs(6))
    code = ("import sys; sys.modules['shapely'] = None\n"
            "from map2map.cli.main import main\n"
            f"rc = main(['train', 'ba', '--data', {str(data)!r},"
            f" '--out', {str(tmp_path / 'run')!r}, '--epochs', '1', '--size', '16',"
            " '--batch', '4', '--g-channels', '8',"
            " '--d-channels', '8', '--d-layers', '2', '--device', 'cpu', '--quiet'])\n"
            "sys.exit(rc or ('shapely' in sys.modules and sys.modules['shapely'] is not None))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=240)
    assert out.returncode == 0, out.stderr[-2000:]
    assert (tmp_path / "run" / "model.safetensors").is_file()


def test_import_map2map_does_not_import_torch():
    code = "import sys, map2map; map2map.__version__; print('torch' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


def test_demo_stage_autocorrects_the_slam_map(tmp_path, capsys):
    from types import SimpleNamespace

    from map2map.demo import STAGES, DemoContext, stage_autocorrect

    names = [n for n, _ in STAGES]
    assert names.index("slam") < names.index("autocorrect") < names.index("evaluate")
    ctx = DemoContext(out=tmp_path, seed=0)
    stage_autocorrect(ctx)
    assert "skipped" in capsys.readouterr().out and not ctx.written
    m = OccupancyMap(_pairs().b[0], 0.05, (1.0, 2.0, 0.0))
    ctx.sim = SimpleNamespace(slam_map_plan=m)
    stage_autocorrect(ctx)
    assert ctx.autocorrected.shape == m.shape
    assert {p.name for _, p in ctx.written} == {
        "cad.yaml",
        "cad.pgm",
        "walls.dxf",
        "before_after.png",
    }
    assert all(p.is_file() for _, p in ctx.written)


def test_autocorrect_deskews_rotated_maps_and_rotates_back():
    import cv2

    n = 240
    data = np.full((n, n), UNKNOWN, np.uint8)
    data[60:180, 50:190] = FREE
    for r in (60, 179):
        data[r, 50:190] = OCCUPIED
    for c in (50, 120, 189):
        data[60:180, c] = OCCUPIED
    rot = cv2.getRotationMatrix2D(((n - 1) / 2, (n - 1) / 2), 25, 1.0)
    tilted = cv2.warpAffine(data, rot, (n, n), flags=cv2.INTER_NEAREST, borderValue=UNKNOWN)
    m = OccupancyMap(tilted, 0.05)
    (res,) = autocorrect_many([m], _Identity())
    assert res.map.meta["autocorrect"]["deskew_deg"] == pytest.approx(-25, abs=2)
    assert res.map.shape == m.shape
    # walls come back where the tilted input has them (the output is in the input's frame)
    from scipy import ndimage

    near = ndimage.distance_transform_edt(tilted != OCCUPIED)
    assert np.median(near[res.map.data == OCCUPIED]) <= 2.0
    # segments follow the tilted walls (about 25 degrees off the axes), not the grid
    seg = np.asarray(res.map.meta["autocorrect"]["segments_px"])
    ang = np.degrees(np.arctan2(seg[:, 3] - seg[:, 1], seg[:, 2] - seg[:, 0])) % 90
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    along = np.minimum(np.abs(ang - 25), np.abs(ang - 65)) < 5   # +-25 deg, mod 90
    assert length[along].sum() >= 0.9 * length.sum()


def test_ctrl_c_checkpoints_mid_epoch_and_resume_is_exact(monkeypatch, tmp_path):
    """Ctrl-C after the first batch: a checkpoint at batch 1 of epoch 1, and --resume ends
    with the weights of an uninterrupted run."""
    import os
    import signal

    data = _pairs(14)                                  # 12 train pairs: 3 batches of 4
    cfg = dict(TINY, epochs=1)
    T.train_ba(data, tmp_path / "whole", TrainConfig(**cfg), progress=False, figures=False)
    real_build = T.build_networks
    calls = {"n": 0}

    def build(c):
        g, dd, dr = real_build(c)

        def hook(module, inputs, output):
            calls["n"] += 1
            if calls["n"] == 1:                       # during the first batch
                os.kill(os.getpid(), signal.SIGINT)

        g.register_forward_hook(hook)
        return g, dd, dr

    monkeypatch.setattr(T, "build_networks", build)
    with pytest.raises(KeyboardInterrupt):
        T.train_ba(data, tmp_path / "cut", TrainConfig(**cfg), progress=False, figures=False)
    from map2map.learn.training.checkpoint import load_checkpoint

    _, state = load_checkpoint(tmp_path / "cut" / "last.safetensors")
    assert (state["epoch"], state["batch"]) == (0, 1)
    monkeypatch.setattr(T, "build_networks", real_build)
    T.train_ba(data, tmp_path / "cut", resume=True, progress=False, figures=False)
    a = _weights(tmp_path / "whole" / "last.safetensors")
    b = _weights(tmp_path / "cut" / "last.safetensors")
    for k in a:
        assert torch.equal(a[k], b[k]), k


def test_output_head_and_logits_stay_float32_under_bf16_autocast():
    from map2map.learn.nets.networks import MultiScaleDiscriminator, UNetGenerator

    g = UNetGenerator(16, channels=8)
    d = MultiScaleDiscriminator(1, channels=8, n_layers=2)
    x = torch.zeros(2, 1, 16, 16)
    with torch.autocast("cpu", dtype=torch.bfloat16):
        y = g(x)
        feats = d(y)
        loss = L.gan_real_fake_3_4(feats, feats, side="d")
    assert y.dtype == torch.float32
    assert feats[0][0].dtype == torch.bfloat16          # the body runs in bf16
    assert all(f[-1].dtype == torch.float32 for f in feats) and loss.dtype == torch.float32


def test_generator_fade_in_blends_resolutions():
    """Issue #15 hook: with alpha the finest block fades in; 0 is the coarser path."""
    from map2map.learn.nets.networks import UNetGenerator, area_downsample

    torch.manual_seed(0)
    g = UNetGenerator(32, channels=8, min_size=16)
    x = torch.rand(1, 1, 32, 32) * 2 - 1
    coarse = g(area_downsample(x, 16))
    up = torch.nn.functional.interpolate(torch.atanh(coarse.clamp(-0.999, 0.999)),
                                         scale_factor=2, mode="bilinear", align_corners=False)
    faded0 = g(x, alpha=torch.tensor(0.0))
    assert torch.allclose(torch.atanh(faded0.clamp(-0.999, 0.999)), up, atol=1e-3)
    assert not torch.allclose(g(x, alpha=torch.tensor(1.0)), faded0)
    assert torch.allclose(g(x, alpha=torch.tensor(1.0)), g(x))


def test_upsample2x_layout_choice_and_values():
    """The decoder's x2 upsampling: channels-last only for CUDA tensors with many maps of
    few pixels (where PyTorch's NCHW kernel starves); the values never depend on the layout
    (on CPU the channels-last kernel is checked against the NCHW one)."""
    from map2map.learn.nets.networks import _channels_last_faster, upsample2x

    meta = torch.empty(1024, 64, 16, 16, device="meta")
    assert not _channels_last_faster(torch.empty(4, 64, 4, 4))  # CPU: never
    assert not _channels_last_faster(meta)  # not CUDA either
    x = torch.rand(8, 32, 4, 4)
    ref = torch.nn.functional.interpolate(x, scale_factor=2, mode="bilinear",
                                          align_corners=False)
    assert torch.equal(upsample2x(x), ref)
    cl = upsample2x(x.contiguous(memory_format=torch.channels_last))
    assert torch.allclose(cl, ref, atol=1e-6, rtol=0)


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs CUDA")
def test_upsample2x_on_cuda_equals_interpolate():
    from map2map.learn.nets.networks import _channels_last_faster, upsample2x

    for shape in ((1024, 64, 16, 16), (64, 32, 128, 128), (4, 1, 8, 8)):
        x = torch.randn(*shape, device="cuda", dtype=torch.bfloat16)
        ref = torch.nn.functional.interpolate(x, scale_factor=2, mode="bilinear",
                                              align_corners=False)
        assert _channels_last_faster(x) == (shape[-1] == 16)
        assert torch.equal(upsample2x(x), ref)


def test_autocorrect_warns_with_what_the_weights_measured():
    """The shipped weights warn on every correction that they were trained on simulated
    maps (and what real maps measured); weights whose note says PROVISIONAL say so; a
    user's own run warns about neither."""
    net = load_model("pretrained")
    m = OccupancyMap(_pairs().b[0], 0.05)
    with pytest.warns(UserWarning, match="simulated SLAM maps only"):
        (res,) = autocorrect_many([m], net)
    assert any("Halmstad" in w for w in res.warnings)
    import dataclasses

    prov = dataclasses.replace(net, header={**net.header, "note": "PROVISIONAL: test"},
                               source="elsewhere.safetensors")
    with pytest.warns(UserWarning, match="provisional"):
        (res,) = autocorrect_many([m], prov)
    own = dataclasses.replace(net, header={**net.header, "note": ""},
                              source="elsewhere.safetensors")
    (res,) = autocorrect_many([m], own)
    assert not any("trained on simulated" in w or "provisional" in w for w in res.warnings)


def test_exporters_write_fp16_with_header_and_refuse_the_other_model(tmp_path):
    """export_model / export_ab_model (one core): float16 tensors, the run's header plus
    the note, a readable .json beside; a file of the other model is refused, nothing
    written."""
    from safetensors import safe_open

    from map2map.core.errors import InputError
    from map2map.learn.ab.model import export_ab_model
    from map2map.learn.ba.model import export_model, pretrained_path

    run = tmp_path / "run"
    T.train_ba(_pairs(6), run, TrainConfig(**{**TINY, "epochs": 1, "samples": 0}),
               progress=False, figures=False)
    dest = export_model(run, tmp_path / "out" / "ba.safetensors", note="exported")
    with safe_open(str(dest), "pt") as f:
        assert {f.get_tensor(k).dtype for k in f.keys()} == {torch.float16}
    head = load_model(dest).header
    assert head["note"] == "exported" and head["epochs_trained"] == 1
    assert head == load_model(run).header | {"note": "exported"}
    assert json.loads(dest.with_suffix(".json").read_text()) == head
    with pytest.raises(InputError):
        export_ab_model(pretrained_path(), tmp_path / "ab.safetensors")
    assert not (tmp_path / "ab.safetensors").exists()


def test_cli_train_on_one_pair_without_val_warns_and_prints_a_rate(tmp_path, capsys):
    """One clean pair, no 'val' split: trained silently and printed 'at 0 img/s'."""
    one = _pairs(3)
    data = tmp_path / "one.npz"
    save_packed(data, PackedPairs(one.a[:1], one.b[:1], np.array(["p0"]), np.array(["train"])))
    rc = main(["train", "ba", "--data", str(data), "--out", str(tmp_path / "run"),
               "--epochs", "1", "--size", "16", "--batch", "1", "--g-channels", "8",
               "--d-channels", "8", "--d-layers", "2", "--device", "cpu", "--quiet"])
    err = capsys.readouterr().err
    assert rc == 0, err
    warned = [ln for ln in err.splitlines() if ln.startswith("map2map: warning:")]
    assert len(warned) == 2, err
    assert "only 1 training pair: fewer than 400" in warned[0]
    assert "no 'val' pairs: the sample grids" in warned[1]
    (summary,) = [ln for ln in err.splitlines() if ln.startswith("trained 1 epochs at ")]
    rate = summary.split(" at ")[1].split(" img/s")[0]
    assert float(rate) > 0, summary


@pytest.mark.parametrize("channels_last", [True, False])
def test_place_networks_layout_follows_config(channels_last):
    """Under amp the networks go channels-last unless ``channels_last=False`` (``--nchw``)."""
    from map2map.learn.ba.config import BAConfig
    from map2map.learn.training.loop import place_networks

    cfg = BAConfig(size=32, g_channels=4, g_max_channels=8, d_channels=4, d_layers=2,
                      channels_last=channels_last)
    nets = T.build_networks(cfg)
    place_networks(nets, torch.device("cpu"), True, cfg)
    w = next(p for p in nets[0].parameters() if p.dim() == 4 and p.shape[1] > 1
             and p.shape[-1] > 1)
    assert w.is_contiguous(memory_format=torch.channels_last) is channels_last
    assert w.is_contiguous() is not channels_last
    assert BAConfig.from_dict(cfg.to_dict()).channels_last is channels_last
    assert BAConfig.from_dict({"size": 32}).channels_last  # older configs: channels-last
