"""The demo says what it does: real SLAM where it says SLAM, figures in a named frame,
an index of its folder (issue 11 item 5)."""

from __future__ import annotations

import html.parser
import re

import numpy as np
from _parametric_plans import two_rooms
from scipy import ndimage

from map2map.core.grid import OccupancyMap
from map2map.jobs.simulate import SimulateSpec, simulate
from map2map.jobs.slam import figure_frame
from map2map.robotlog.logs import load_log
from map2map.slam.offline import run_slam


class _Links(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.href: list[str] = []
        self.src: list[str] = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "a" and "href" in a:
            self.href.append(a["href"])
        if tag == "img" and "src" in a:
            self.src.append(a["src"])


def test_demo_is_honest_and_its_index_lists_every_file(tmp_path, capsys):
    from map2map.demo import STAGES, run_demo

    out = tmp_path / "demo"
    ctx = run_demo(out, seed=0, progress=False, plan=two_rooms(), sim_seconds=10.0)
    printed = capsys.readouterr().out
    # the "simulated SLAM map" is made by the real default mapper, not the oracle
    assert ctx.sim.info["mapper"] == "rbpf" and "oracle" not in printed
    assert ctx.ate["simulate_rbpf"] > 0.0  # an estimated path, not the true poses
    assert "rbpf SLAM map: coverage" in printed
    # the evaluation names what made each map, and evaluates the SLAM maps
    evaluated = re.findall(r"^evaluate (\S+) \(([^)]+)\)", printed, re.M)
    assert [n for n, _ in evaluated][:2] == ["simulate_rbpf", "slam_graph"]
    assert "rbpf SLAM map" in evaluated[0][1] and "graph SLAM" in evaluated[1][1]
    assert all("not SLAM" in what for n, what in evaluated if n.startswith("parametric"))

    on_disk = {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()}
    assert {"index.html", "README.md"} <= on_disk
    assert {p.relative_to(out).as_posix() for _, p in ctx.written} == on_disk
    page = (out / "index.html").read_text(encoding="utf-8")
    links = _Links()
    links.feed(page)
    # every file the demo wrote is linked (but the index itself), every link resolves
    assert set(links.href) == on_disk - {"index.html"}
    assert all((out / h).is_file() for h in links.href + links.src)
    pictures = {f for f in on_disk if f.endswith((".png", ".gif"))}
    assert set(links.src) == pictures
    readme = (out / "README.md").read_text(encoding="utf-8")
    md_links = set(re.findall(r"\]\(([^)]+)\)", readme))
    assert md_links == on_disk - {"index.html", "README.md"}
    # one section per step, with its key numbers
    for name, _ in STAGES:
        assert re.search(rf"<h2>\d+\. {name} \(", page), name
        assert f". {name} (" in readme
        assert ctx.summary[name], name
    assert "coverage" in page and "ATE" in page and "walls mean" in page


def test_slam_figure_is_drawn_in_the_plan_frame_of_a_simulated_run(tmp_path):
    plan = two_rooms()
    run = simulate(
        SimulateSpec(plan, tmp_path / "run", seed=1, duration=8.0, mapper="oracle",
                     start=(1.5, 2.0, np.pi / 2), figures=False, progress=False)
    )  # fmt: skip
    log = load_log(tmp_path / "run")
    frame = log.plan_start_pose()
    assert np.allclose(frame, run.result.start)
    res = run_slam(log, "graph")
    near_wall = ndimage.binary_dilation(plan.occupied, iterations=2)

    def on_plan_walls(m: OccupancyMap) -> float:
        return float(near_wall[m.occupied].mean())

    shown, traj, _, text = figure_frame(res, frame, plan)
    assert text.startswith("plan frame") and shown.shape == plan.shape
    assert on_plan_walls(shown) > 0.9
    true = run.result.true_poses
    assert np.hypot(*(traj[0, :2] - true[0, :2])) < 0.05  # the path starts at the true start
    # without the start pose (a recorded log) it stays in the map frame and says so
    raw, traj0, _, text = figure_frame(res)
    assert text.startswith("map frame = first pose")
    assert np.allclose(traj0[0, :2], 0.0, atol=0.05)
    from map2map.sim.mapping import resample_to_frame

    unplaced = resample_to_frame(raw, (0.0, 0.0, 0.0), plan)  # map frame read as plan frame
    assert on_plan_walls(unplaced) < 0.6


def test_an_interrupted_demo_leaves_no_folder_and_keeps_the_old_one(tmp_path, monkeypatch):
    import map2map.demo as demo

    out = tmp_path / "demo"
    out.mkdir()
    (out / "old.txt").write_text("an earlier run")

    def boom(ctx):
        (ctx.out / "half.txt").write_text("half-written")
        raise KeyboardInterrupt

    monkeypatch.setattr(demo, "STAGES", [("plan", demo.stage_plan), ("boom", boom)])
    try:
        demo.run_demo(out, seed=0, progress=False, plan=two_rooms(), verbose=False)
    except KeyboardInterrupt:
        pass
    else:  # pragma: no cover
        raise AssertionError("the interruption was swallowed")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["demo"]
    assert sorted(p.name for p in out.iterdir()) == ["old.txt"]


def test_the_demo_says_what_reference_58_is(capsys):
    """The index cited "[58]" bare: it now says it is the thesis's reference and what the
    method taken from it does; so do deform's --help and the demo's file labels."""
    import inspect

    import pytest

    from map2map.cli.main import main
    from map2map.demo import _description, stage_parametric

    text = _description(stage_parametric)
    assert "the thesis takes from its reference [58]" in text
    assert "E_lin = 0.09 dl + sigma, E_ang = 0.095 dtheta + alpha" in text
    assert "additive method of the thesis's ref. [58]" in inspect.getsource(stage_parametric)
    with pytest.raises(SystemExit):
        main(["deform", "--help"])
    helptext = " ".join(capsys.readouterr().out.split())
    at = [m.start() for m in re.finditer(re.escape("[58]"), helptext)]
    assert len(at) == 2
    assert all("thesis" in helptext[max(0, i - 40):i] for i in at), helptext
