"""Coverage from the robot's own exploration (map2map.learn.ab.coverage) and its wiring into
synthesize / synthesize_squares / the CLI: seeded per hypothesis, separable from the
drift's route, the defaults unchanged. Tiny plans, short explorations."""

from __future__ import annotations

import numpy as np
import pytest

from map2map.core.errors import InputError
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.learn.ab.coverage import (
    ExploreParams,
    coverage_options,
    explore_plan,
    explore_rng,
    free_from_rays,
    hide_unseen,
)

SHORT = ExploreParams(duration=30.0)


def _plan() -> OccupancyMap:
    """Two rooms, 3.1 x 2.1 m at 0.07 m, no door between them: one exploration sees one."""
    data = np.full((30, 44), UNKNOWN, np.uint8)
    data[4:26, 6:40] = FREE
    data[4, 6:40] = data[25, 6:40] = OCCUPIED
    data[4:26, 6] = data[4:26, 39] = data[4:26, 20] = OCCUPIED
    return OccupancyMap(data, resolution=0.07, origin=(1.5, -2.0, 0.0))


def test_exploration_is_seeded_and_sees_one_room():
    plan = _plan()
    a = explore_plan(plan, explore_rng(3, 0), SHORT)
    b = explore_plan(plan, explore_rng(3, 0), SHORT)
    assert np.array_equal(a.seen, b.seen) and np.array_equal(a.trajectory.x, b.trajectory.x)
    assert a.seed == b.seed
    starts = {explore_plan(plan, explore_rng(3, k), SHORT).start[:2] for k in range(4)}
    assert len(starts) > 1                                       # each hypothesis its own start
    assert a.seen.shape == plan.shape
    left, right = a.seen[5:25, 8:19].mean(), a.seen[5:25, 22:38].mean()
    assert max(left, right) > 0.9 and min(left, right) < 0.05    # the closed room stays unseen
    assert a.trajectory.t[-1] <= 30.0 + 1e-9
    r, c = plan.world_to_pixel(a.trajectory.x, a.trajectory.y)
    assert np.all(plan.data[r, c] == FREE)                       # driven in free space


def test_hide_unseen_keeps_a_band_and_checks_shapes():
    m = np.full((5, 10), FREE, np.uint8)
    m[:, 4] = OCCUPIED
    seen = np.zeros((5, 10), bool)
    seen[:, :4] = True                                          # saw up to the wall's face
    out = hide_unseen(m, seen, 1)
    assert np.all(out[:, :5] == m[:, :5]) and np.all(out[:, 6:] == UNKNOWN)
    assert np.array_equal(hide_unseen(m, seen, 0)[:, 4], np.full(5, UNKNOWN))
    assert np.all(hide_unseen(m, np.zeros_like(seen), 3) == UNKNOWN)
    with pytest.raises(ValueError):
        hide_unseen(m, seen[:, :3], 1)
    assert ExploreParams().margin(2.06) == 3 and ExploreParams(margin_px=0).margin(2.0) == 0
    with pytest.raises(InputError, match="coverage"):
        coverage_options("some", "tour")
    with pytest.raises(InputError, match="drift_route"):
        coverage_options("none", "roadmap")
    with pytest.raises(InputError):
        ExploreParams(duration=0.0)


def test_free_from_rays_takes_the_rays_free_space_and_keeps_the_network_walls():
    # the network: a room 2..9 x 1..8 with a wall at column 9, its corner rounded off
    # (unknown) and a cloud of free space past the rays at row 8
    m = np.full((10, 12), UNKNOWN, np.uint8)
    m[1:9, 1:9] = FREE
    m[1, 1] = m[1, 2] = m[2, 1] = UNKNOWN
    m[:, 9] = OCCUPIED
    # the rays crossed rows 1-7, columns 1-8, and hit the wall (column 9) and the top row
    free = np.zeros_like(m, bool)
    free[1:8, 1:9] = True
    seen = free.copy()
    seen[1:8, 9] = True
    seen[0, 1:9] = True
    out = free_from_rays(m, seen, free, margin_px=1, reach_px=0, hits_px=1.5)
    assert np.all(out[1:3, 1:3] == FREE)                       # the rounded corner: free
    assert np.all(out[8, 1:9] == UNKNOWN)                      # the cloud past the rays
    assert np.all(out[0:9, 9] == OCCUPIED)                      # the network's wall, near seen
    assert np.all(out[9, 9] == UNKNOWN)                         # ... not far from any
    assert np.all(out[0, 1:8] == OCCUPIED)                     # a face it missed: drawn
    assert out[0, 8] == UNKNOWN                               # next to its wall: not doubled
    # reach: the network's free kept a pixel past the rays; no hits drawn
    out2 = free_from_rays(m, seen, free, margin_px=1, reach_px=1, hits_px=None)
    assert np.all(out2[8, 1:9] == FREE) and np.all(out2[0, 1:8] == UNKNOWN)
    with pytest.raises(ValueError):
        free_from_rays(m, seen[:, :3], free, 1)


@pytest.fixture(scope="module")
def drawer():
    """A Model_AB stand-in that draws its input plan (untrained nets draw next to nothing)."""
    pytest.importorskip("torch")
    import torch

    from map2map.learn.ab.model import ABModel
    from map2map.learn.nets.progressive import StochasticUNet
    from map2map.learn.training.data import reduce_input

    torch.manual_seed(0)
    net = ABModel(StochasticUNet(size=32, channels=8, min_size=16), resolution=32, alpha=1.0,
                  data_size=64, header={"target_wall_px": 2.0}, source="drawer")

    def sample_many(inputs, samples=1, seed=0):
        x = reduce_input(np.asarray(inputs, np.uint8), net.resolution, "area")
        return np.repeat(x[:, None].astype(np.float32), samples, axis=1)

    net.sample_many = sample_many
    return net


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_synthesize_coverage_hides_the_unseen_room_and_route_is_separable(drawer):
    from map2map.learn.ab.drift import apply_drift, drift_field, drift_rng
    from map2map.learn.ab.synthesize import synthesize

    plan = _plan()
    old = {"traces": "none"}                  # the walls without LIDAR traces (session 11)
    base = synthesize(plan, drawer, samples=2, seed=4, drift="none", coverage="none", **old)
    cov = synthesize(plan, drawer, samples=2, seed=4, drift="none", coverage="explore",
                     explore=SHORT, **old)
    again = synthesize(plan, drawer, samples=2, seed=4, drift="none", coverage="explore",
                       explore=SHORT, **old)
    wall_px = 2.0 * 44 / 64                                      # the square is the plan's width
    for k, (b, c, a) in enumerate(zip(base.maps, cov.maps, again.maps, strict=True)):
        assert np.array_equal(c.data, a.data)                     # same seed, same bytes
        ex = explore_plan(plan, explore_rng(4, k), SHORT)
        assert np.array_equal(c.data, hide_unseen(b.data, ex.seen, SHORT.margin(wall_px)))
        assert np.count_nonzero(c.data == UNKNOWN) > np.count_nonzero(b.data == UNKNOWN) + 100
        meta = c.meta["synthesize"]
        assert meta["coverage"] == "explore" and meta["exploration"]["seed"] == ex.seed
        assert "coverage" not in b.meta["synthesize"]             # coverage none: meta as before
    # (a) alone: the drift field is the tour's, as without coverage
    par = {"drift": "parametric", **old}
    drift = synthesize(plan, drawer, samples=1, seed=4, coverage="none", **par)
    both = synthesize(plan, drawer, samples=1, seed=4, coverage="explore", explore=SHORT, **par)
    route = synthesize(plan, drawer, samples=1, seed=4, coverage="none", drift_route="explore",
                       explore=SHORT, **par)
    ex = explore_plan(plan, explore_rng(4, 0), SHORT)
    tour = drift_field(plan, drift_rng(4, 0))
    assert np.array_equal(drift.maps[0].data, apply_drift(base.maps[0].data, tour))
    assert np.array_equal(both.maps[0].data, apply_drift(cov.maps[0].data, tour))
    # (b) alone: nothing hidden, the drift driven along the exploration's path
    along = drift_field(plan, drift_rng(4, 0), trajectory=ex.trajectory)
    assert np.array_equal(route.maps[0].data, apply_drift(base.maps[0].data, along))
    assert not np.array_equal(route.maps[0].data, drift.maps[0].data)
    with pytest.raises(InputError, match="coverage"):
        synthesize(plan, drawer, coverage="all")


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_synthesize_rays_takes_free_space_from_each_hypothesis_exploration(drawer):
    from map2map.learn.ab.synthesize import synthesize

    plan = _plan()
    kw = {"samples": 2, "seed": 4, "drift": "none", "traces": "none", "explore": SHORT}
    base = synthesize(plan, drawer, coverage="none", **kw)
    rays = synthesize(plan, drawer, coverage="rays", **kw)
    again = synthesize(plan, drawer, coverage="rays", **kw)
    margin = SHORT.margin(2.0 * 44 / 64)
    for k, (b, r, a) in enumerate(zip(base.maps, rays.maps, again.maps, strict=True)):
        assert np.array_equal(r.data, a.data)                     # same seed, same bytes
        ex = explore_plan(plan, explore_rng(4, k), SHORT)
        assert np.array_equal(r.data, free_from_rays(b.data, ex.seen, ex.free, margin,
                                                     SHORT.reach_px, SHORT.hits_px))
        assert np.all(r.data[ex.free & (b.data != OCCUPIED)] == FREE)
        assert r.meta["synthesize"]["coverage"] == "rays"


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_synthesize_squares_explores_each_square_at_its_resolution(drawer):
    from map2map.learn.ab.drift import DriftParams, drift_maps
    from map2map.learn.ab.synthesize import synthesize_squares

    plans = np.full((2, 64, 64), UNKNOWN, np.uint8)
    for p in plans:
        p[4:60, 4:60] = FREE
        p[4:60, [4, 5, 58, 59]] = OCCUPIED
        p[[4, 5, 58, 59], 4:60] = OCCUPIED
        p[4:60, 30:32] = OCCUPIED                                # two closed rooms
    res = [0.05, 0.06]
    none = synthesize_squares(drawer, plans, seed=1, resolution=res, drift="none")
    got = synthesize_squares(drawer, plans, seed=1, resolution=res, coverage="explore",
                             drift_route="explore", explore=SHORT)
    assert np.array_equal(got, synthesize_squares(drawer, plans, seed=1, resolution=res,
                                                  coverage="explore", drift_route="explore",
                                                  explore=SHORT))
    hidden, trajs = [], []
    for i in range(2):
        ex = explore_plan(OccupancyMap(plans[i], res[i]), explore_rng(1, i), SHORT)
        hidden.append(hide_unseen(none[i], ex.seen, SHORT.margin(2.0)))
        trajs.append(ex.trajectory)
    want, _ = drift_maps(np.stack(hidden), plans, res, 1, DriftParams(), trajectories=trajs)
    assert np.array_equal(got, want)
    # one of the two rooms unseen in each square
    assert all(np.mean(g[8:56, 8:56] == UNKNOWN) > 0.3 for g in got)
    assert np.array_equal(synthesize_squares(drawer, plans, seed=1, resolution=res),
                          drift_maps(none, plans, res, 1, DriftParams())[0])


def test_cli_synthesize_coverage(tmp_path, capsys, drawer, monkeypatch):
    import json

    from map2map.cli.main import main
    from map2map.learn.ab import synthesize as S
    from map2map.maps.formats import save_map

    monkeypatch.setattr(S, "load_ab_model", lambda model, device="cpu": drawer)
    save_map(_plan(), tmp_path / "plan.yaml")
    out = tmp_path / "hyps"
    assert main(["synthesize", str(tmp_path / "plan.yaml"), "--out", str(out), "--samples",
                 "1", "--no-figure", "--model", "pretrained", "--coverage", "explore",
                 "--drift-route", "explore"]) == 0
    s = json.loads((out / "plan_synthesize.json").read_text())
    assert (s["coverage"], s["drift_route"]) == ("explore", "explore")
    assert s["unknown_share"][0] > 0.5
    with pytest.raises(SystemExit) as exc:                       # argparse's choices
        main(["synthesize", str(tmp_path / "plan.yaml"), "--out", str(tmp_path / "b"),
              "--coverage", "all"])
    assert exc.value.code == 2
    assert "Traceback" not in capsys.readouterr().err
