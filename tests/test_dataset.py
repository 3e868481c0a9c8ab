"""map2map dataset: build (deterministic, resumable, local/Dask, failures), features,
cleaner, export. Tiny plans and short simulations keep it fast."""

from __future__ import annotations

import ctypes
import os
import signal
import socket
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from map2map.core.errors import InputError
from map2map.core.grid import OccupancyMap
from map2map.datasets.build import build_dataset, dataset_status, split_for_plan
from map2map.datasets.clean import apply_cleaner, clean_dataset, load_cleaner, read_labels
from map2map.datasets.export import export_dataset
from map2map.datasets.features import (
    FEATURE_NAMES,
    count_holes,
    grey_white_neighbours,
    pair_features,
)
from map2map.datasets.packed import load_packed
from map2map.datasets.pair import BuildParams, run_pair
from map2map.maps.ros import save_ros_map

REPO = Path(__file__).resolve().parents[1]
PARAMS = BuildParams(source="both", duration=12.0, size=32, fov=360.0)
COUNT = 6


def _room(w_px: int, h_px: int, door: bool = True) -> OccupancyMap:
    d = np.full((h_px + 8, w_px + 8), 127, np.uint8)
    d[2:-2, 2:-2] = 0
    d[4:-4, 4:-4] = 255
    mid = (w_px + 8) // 2
    d[4:-4, mid] = 0  # a divider wall ...
    if door:
        d[8:26, mid] = 255  # ... with a 0.9 m opening
    return OccupancyMap(d, 0.05)


@pytest.fixture(scope="module")
def plans(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("plans")
    save_ros_map(_room(70, 50), folder / "a_room.yaml")
    save_ros_map(_room(60, 40), folder / "b_room.yaml")
    save_ros_map(_room(80, 44), folder / "c_room.yaml")
    return folder


@pytest.fixture(scope="module")
def reference(plans, tmp_path_factory) -> Path:
    """The uninterrupted, in-process build every other build must equal byte for byte."""
    ds = tmp_path_factory.mktemp("ref") / "DS"
    s = build_dataset(ds, str(plans), COUNT, 5, PARAMS, workers=0, progress=False)
    assert s.done == COUNT and s.failed == 0
    return ds


def _tree(ds: Path) -> dict[str, bytes]:
    root = ds / "pairs"
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file()}  # fmt: skip


def _assert_same(ds: Path, ref: Path) -> None:
    a, b = _tree(ds), _tree(ref)
    assert sorted(a) == sorted(b)
    diff = [k for k in a if a[k] != b[k]]
    assert not diff, f"files differ: {diff[:5]}"


# ------------------------------------------------------------------ features
def test_features_on_hand_made_maps():
    cad = np.full((10, 10), 255, np.uint8)
    cad[0, :] = cad[-1, :] = cad[:, 0] = cad[:, -1] = 0  # 36 wall pixels, 64 free
    cad[4, 4] = 0  # one hole (a column)
    slam = cad.copy()
    slam[1:9, 6:9] = 127  # 24 unknown: the right part unexplored
    slam[2, 2] = 0  # another column seen
    f = dict(zip(FEATURE_NAMES, pair_features(cad, slam).tolist(), strict=True))
    assert (f["cad_black"], f["cad_grey"], f["cad_white"]) == (37, 0, 63)
    assert (f["slam_black"], f["slam_grey"], f["slam_white"]) == (38, 24, 38)
    assert (f["diff_black"], f["diff_grey"], f["diff_white"]) == (1, 24, -25)
    assert f["diff_ratio_black_white"] == pytest.approx(38 / 38 - 37 / 63)
    assert f["diff_ratio_grey_white"] == pytest.approx(24 / 38 - 0)
    assert f["diff_ratio_black_grey"] == pytest.approx(38 / 24 - 37 / 1)  # 0 grey counts as 1
    assert count_holes(cad) == 1 and count_holes(slam) == 2
    assert f["diff_holes"] == 1
    # the unknown block's border with free space: 8 pixels along column 5
    assert f["slam_grey_white_nb"] == 8 and f["cad_grey_white_nb"] == 0
    assert f["diff_grey_white_nb"] == 8


def test_holes_by_boundary_tracing():
    m = np.full((12, 12), 255, np.uint8)
    m[2:4, 2:4] = 0  # hole 1
    m[6:9, 6:9] = 127  # hole 2 (unknown counts: not white)
    m[7, 7] = 255  # an island inside hole 2 is not a hole
    m[0:3, 10:12] = 0  # touches the border: not a hole
    assert count_holes(m) == 2
    assert count_holes(np.zeros((5, 5), np.uint8)) == 0
    assert grey_white_neighbours(np.array([[127, 255], [255, 255]], np.uint8)) == 2


# --------------------------------------------------------------------- build
def test_reference_build_contents(reference):
    st = dataset_status(reference)
    assert st["counts"] == {"done": COUNT}
    folder = reference / "pairs" / "000001"  # a parametric pair
    names = sorted(p.name for p in folder.iterdir())
    assert names == ["A.pgm", "A.png", "A.yaml", "B.pgm", "B.png", "B.yaml", "displacement.npz",
                     "meta.json"]  # fmt: skip
    assert "displacement.npz" not in os.listdir(reference / "pairs" / "000000")
    with np.load(folder / "displacement.npz") as z:
        assert z["dx"].dtype == np.float32
    rows = (
        sqlite3.connect(reference / "manifest.sqlite")
        .execute("SELECT plan_id, split, coverage, stop_reason, wall_seconds FROM pairs")
        .fetchall()
    )
    for plan_id, split, cov, stop, secs in rows:
        assert split == split_for_plan(plan_id)
        assert 0 <= cov <= 1 and stop and secs > 0
    assert (reference / "figures" / "contact_sheet.png").stat().st_size > 0
    assert (reference / "figures" / "histograms.png").stat().st_size > 0


def test_same_pairs_with_two_workers(plans, reference, tmp_path):
    # fork: quicker to start; the command-line builds of the kill test use spawn
    build_dataset(tmp_path / "DS", str(plans), COUNT, 5, PARAMS, workers=2, progress=False,
                  figures=False, start_method="fork")  # fmt: skip
    _assert_same(tmp_path / "DS", reference)


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "map2map", *args]


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(REPO / "src") + os.pathsep + env.get("PYTHONPATH", "")
    return env


def test_resume_after_kill_9(plans, reference, tmp_path):
    ds = tmp_path / "DS"
    args = _cli("dataset", "build", "--out", str(ds), "--plans", str(plans), "--count",
                str(COUNT), "--seed", "5", "--source", "both", "--duration", "12", "--size",
                "32", "--fov", "360", "--workers", "1", "--quiet", "--no-figures")  # fmt: skip
    kills = 0
    for _ in range(2):  # kill it twice, each time once at least one more pair is in
        before = _done(ds)
        proc = subprocess.Popen(args, env=_env(), start_new_session=True,
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)  # fmt: skip
        deadline = time.monotonic() + 120
        while proc.poll() is None and _done(ds) <= before and time.monotonic() < deadline:
            time.sleep(0.05)
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)  # the build and its worker, mid-pair
            kills += 1
        proc.wait(30)
    assert kills >= 1 and _done(ds) < COUNT
    done = subprocess.run(args, env=_env(), capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    _assert_same(ds, reference)
    assert dataset_status(ds)["counts"] == {"done": COUNT}
    # the same command again: nothing left to do, nothing changes
    again = subprocess.run(args, env=_env(), capture_output=True, text=True, timeout=300)
    assert again.returncode == 0 and "this run: 0 made" in again.stdout
    # other settings on the same dataset are refused, with one line and exit 2
    bad = subprocess.run([*args[:-1], "--fov", "180"], env=_env(), capture_output=True,
                         text=True, timeout=300)  # fmt: skip
    assert bad.returncode == 2 and "fov 360.0 -> 180.0" in bad.stderr
    assert "Traceback" not in bad.stderr


def test_resume_after_a_kill_in_either_write_window(plans, reference, tmp_path):
    """The two moments a kill -9 can leave traces, made deterministic: mid-write (a
    temporary folder) and between the rename and the manifest's transaction (a pair
    folder without its row). The next run removes both and makes those pairs again."""
    ds = tmp_path / "DS"
    build_dataset(ds, str(plans), 2, 5, PARAMS, workers=0, progress=False, figures=False)
    with sqlite3.connect(ds / "manifest.sqlite") as con:
        con.execute("DELETE FROM pairs WHERE idx = 1")  # renamed, never recorded
    half = ds / "pairs" / ".tmp-000002-4242"
    half.mkdir()
    (half / "A.pgm").write_bytes(b"P5 half a file")
    (ds / "pairs" / "000001" / "B.png").write_bytes(b"torn")  # an unrecorded folder is not trusted
    s = build_dataset(ds, str(plans), 3, 5, PARAMS, workers=0, progress=False, figures=False)
    assert (s.made_now, s.done) == (2, 3)
    ref = {k: v for k, v in _tree(reference).items() if k[:6] in ("000000", "000001", "000002")}
    assert _tree(ds) == ref


def _done(ds: Path) -> int:
    db = ds / "manifest.sqlite"
    if not db.exists():
        return 0
    try:
        with sqlite3.connect(db, timeout=5) as con:
            return con.execute("SELECT COUNT(*) FROM pairs WHERE status='done'").fetchone()[0]
    except sqlite3.OperationalError:
        return 0


def test_bad_plans_fail_and_the_build_goes_on(plans, tmp_path):
    folder = tmp_path / "plans"
    folder.mkdir()
    save_ros_map(_room(60, 40), folder / "good.yaml")
    save_ros_map(OccupancyMap(np.zeros((40, 40), np.uint8), 0.05), folder / "solid.yaml")
    tiny = np.full((12, 12), 0, np.uint8)
    tiny[5:7, 5:7] = 255  # free, but no room for the robot
    save_ros_map(OccupancyMap(tiny, 0.05), folder / "tiny.yaml")
    (folder / "broken.png").write_bytes(b"not a png")
    p = BuildParams(source="simulate", duration=8.0, size=32, fov=360.0)
    s = build_dataset(tmp_path / "DS", str(folder), 4, 0, p, workers=0, progress=False,
                      figures=False)  # fmt: skip
    assert (s.done, s.failed) == (1, 3)
    reasons = {plan: why for _, plan, why in dataset_status(tmp_path / "DS")["failed"]}
    assert "broken" in reasons and "solid" in reasons and "tiny" in reasons
    assert "no free space" in reasons["solid"]
    assert "too small for the robot" in reasons["tiny"]
    out = subprocess.run(_cli("dataset", "status", str(tmp_path / "DS")), env=_env(),
                         capture_output=True, text=True, timeout=120)  # fmt: skip
    assert out.returncode == 0 and out.stdout.count("failed ") >= 3


def crashing_task(spec):
    """Pair 1 kills its worker once (os._exit), pair 2 segfaults every time."""
    marker = Path(os.environ["M2M_CRASH_DIR"]) / f"crashed-{spec.index}"
    if spec.index == 1 and not marker.exists():
        marker.touch()
        os._exit(3)
    if spec.index == 2:
        import faulthandler

        faulthandler.disable()  # pytest's handler would print the crash in the log
        ctypes.string_at(0)  # SIGSEGV
    return run_pair(spec)


def test_dead_workers_are_retried_then_recorded(plans, reference, tmp_path, monkeypatch):
    monkeypatch.setenv("M2M_CRASH_DIR", str(tmp_path))
    s = build_dataset(tmp_path / "DS", str(plans), 4, 5, PARAMS, workers=2, progress=False,
                      figures=False, task=crashing_task, max_attempts=2,
                      start_method="fork")  # fmt: skip
    assert (s.done, s.failed) == (3, 1)
    st = dataset_status(tmp_path / "DS")
    ((idx, _, why),) = st["failed"]
    assert idx == 2 and "SIGSEGV" in why and "2 attempts" in why
    ref = _tree(reference)
    got = _tree(tmp_path / "DS")
    assert got and all(got[k] == ref[k] for k in got)  # pair 1, retried, is byte-identical
    assert any(k.startswith("000001/") for k in got)


# ---------------------------------------------------------------------- dask
def test_dask_local_cluster_gives_the_same_pairs(plans, reference, tmp_path):
    pytest.importorskip("distributed")
    build_dataset(tmp_path / "DS", str(plans), COUNT, 5, PARAMS, workers=2, scheduler="local",
                  progress=False, figures=False)  # fmt: skip
    _assert_same(tmp_path / "DS", reference)


def test_dask_dead_workers_are_retried_then_recorded(plans, reference, tmp_path, monkeypatch):
    """A LocalCluster worker that dies is restarted by its nanny and the pair run again
    (Dask's retries); a pair that kills every worker it runs on is recorded failed."""
    pytest.importorskip("distributed")
    import dask

    monkeypatch.setenv("M2M_CRASH_DIR", str(tmp_path))  # the workers inherit it
    # one retry instead of Dask's three: two deaths make a KilledWorker (quicker test)
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
        kw = dict(workers=1, scheduler="local", progress=False, figures=False,
                  task=crashing_task)  # fmt: skip
        try:
            s = build_dataset(tmp_path / "DS", str(plans), 4, 5, PARAMS, **kw)
        except InputError as exc:
            # on a very loaded machine a nanny can fail to restart its worker (Dask gives
            # up after its connect timeout): the build stops with this error, and the
            # same command continues, as the message says
            assert "run the same command again" in str(exc)
            s = build_dataset(tmp_path / "DS", str(plans), 4, 5, PARAMS, **kw)
    assert (s.done, s.failed) == (3, 1)
    ((idx, _, why),) = dataset_status(tmp_path / "DS")["failed"]
    assert idx == 2 and "dask workers died running it (2 workers" in why
    assert (tmp_path / "crashed-1").exists()  # pair 1 did kill its first worker ...
    ref, got = _tree(reference), _tree(tmp_path / "DS")
    assert any(k.startswith("000001/") for k in got)  # ... and was made on the next one
    assert got and all(got[k] == ref[k] for k in got)


class _FakeFuture:
    def __init__(self, value, log=None, key=""):
        self.value, self.log, self.key = value, log if log is not None else [], key

    def result(self):
        self.log.append(("result", self.key))
        return self.value

    def release(self):
        self.log.append(("release", self.key))

    def cancel(self):
        pass


class _FakeClient:
    """Runs a task when submitted; records how many were in flight at once."""

    def __init__(self, threads: dict):
        self.threads, self.live, self.most, self.log = threads, set(), 0, []

    def nthreads(self):
        return dict(self.threads)

    def run(self, fn):
        return {w: {"malloc_trim": "65536", "profile": w == "w1"} for w in self.threads}

    def submit(self, fn, task, key, pure):
        self.log.append(("submit", key))
        fut = _FakeFuture(fn(task), self.log, key)
        self.live.add(fut)
        self.most = max(self.most, len(self.live))
        return fut

    def wait(self, futures, timeout, return_when):
        from types import SimpleNamespace

        done = {futures[0]}  # one finishes at a time
        self.live -= done
        return SimpleNamespace(done=done)


def test_dask_submission_is_greedy_and_warns_on_threads():
    """No more pairs in flight than the cluster has threads (the next one goes to whichever
    worker frees first), every task run once, in order; threaded workers are warned about."""
    pytest.importorskip("distributed")
    from collections import deque
    from types import SimpleNamespace

    from map2map.datasets.dask_backend import _run

    tasks = [SimpleNamespace(index=i) for i in range(7)]
    got = []
    client = _FakeClient({"w1": 1, "w2": 1})
    _run(client, deque(tasks), lambda t: t.index * 10, lambda t, r, w: got.append(r),
         None, "k", RuntimeError, client.wait)  # fmt: skip
    assert got == [i * 10 for i in range(7)] and client.most == 2
    client = _FakeClient({"w1": 3})
    from map2map.datasets.dask_backend import DaskWarning

    with pytest.warns(DaskWarning, match="3 threads each"):
        _run(client, deque(tasks), lambda t: 0, lambda t, r, w: None, None, "k", RuntimeError,
             client.wait)  # fmt: skip
    assert client.most == 3
    from map2map.datasets.dask_backend import _check_workers

    # a cluster without workers: ours (a LocalCluster) is broken, one's own gets a warning
    with pytest.raises(InputError, match="LocalCluster has had no worker"):
        _run(_FakeClient({}), deque(tasks), abs, None, None, "k", RuntimeError, None,
             local=True, no_worker_s=0.0)  # fmt: skip
    client = _FakeClient({})
    with pytest.warns(DaskWarning, match="no dask worker at tcp://h:1"):
        _run(client, deque(tasks), lambda t: 0, lambda t, r, w: None, None, "k", RuntimeError,
             client.wait, where="tcp://h:1", no_worker_s=0.0)  # fmt: skip
    match = "MALLOC_TRIM_THRESHOLD_=65536.*profiler on .1 of 2"
    with pytest.warns(DaskWarning, match=match):
        _check_workers(_FakeClient({"w1": 1, "w2": 1}))


def test_dask_results_are_fetched_before_the_next_pair_starts():
    """A finished pair is fetched from its worker and released before the next pair is
    submitted: a result left on the worker would be lost if the next pair killed it (and
    the recomputed pair could then be blamed for that death; seen in CI)."""
    pytest.importorskip("distributed")
    from collections import deque
    from types import SimpleNamespace

    from map2map.datasets.dask_backend import _run

    tasks = [SimpleNamespace(index=i) for i in range(3)]
    client = _FakeClient({"w1": 1})
    written = []

    def on_result(t, r, w):
        written.append(t.index)
        client.log.append(("write", f"k-{t.index}"))

    _run(client, deque(tasks), lambda t: t.index, on_result, None, "k", RuntimeError,
         client.wait)  # fmt: skip
    assert written == [0, 1, 2]
    log = client.log
    for i in range(2):  # pair i+1 starts after pair i is fetched and released ...
        assert log.index(("release", f"k-{i}")) < log.index(("submit", f"k-{i + 1}"))
        # ... and before pair i is written (writing overlaps the next computation)
        assert log.index(("submit", f"k-{i + 1}")) < log.index(("write", f"k-{i}"))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


#: The Dask configuration map2map.datasets.dask_backend (and the README) tell users to give
#: their own workers.
WORKER_CONFIG = """\
distributed:
  nanny:
    pre-spawn-environ:
      MALLOC_TRIM_THRESHOLD_: null
  worker:
    profile:
      enabled: false
"""


def test_dask_separate_scheduler_and_worker(plans, reference, tmp_path):
    pytest.importorskip("distributed")
    from map2map.datasets import dask_backend

    assert WORKER_CONFIG in dask_backend.__doc__.replace("\n    ", "\n")  # documented as tested
    (tmp_path / "daskcfg").mkdir()
    (tmp_path / "daskcfg" / "map2map.yaml").write_text(WORKER_CONFIG)
    port = _free_port()
    addr = f"tcp://127.0.0.1:{port}"
    procs = []
    try:
        procs.append(subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
             "--port", str(port), "--no-dashboard"],
            env=_env(), start_new_session=True, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL))  # fmt: skip
        procs.append(subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", addr, "--nthreads", "1",
             "--nworkers", "1", "--no-dashboard", "--host", "127.0.0.1"],
            env={**_env(), "DASK_CONFIG": str(tmp_path / "daskcfg")}, start_new_session=True,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL))  # fmt: skip
        from distributed import Client

        with Client(addr, timeout="60s") as c:
            c.wait_for_workers(1, timeout=60)
        out = subprocess.run(
            _cli("dataset", "build", "--out", str(tmp_path / "DS"), "--plans", str(plans),
                 "--count", str(COUNT), "--seed", "5", "--source", "both", "--duration", "12",
                 "--size", "32", "--fov", "360", "--scheduler", addr, "--quiet",
                 "--no-figures"),
            env=_env(), capture_output=True, text=True, timeout=240)  # fmt: skip
        assert out.returncode == 0, out.stderr
        assert "warning" not in out.stderr  # the configuration above is what it asks for
        _assert_same(tmp_path / "DS", reference)
    finally:
        for p in procs:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait(10)


def test_unreachable_scheduler_is_one_line(plans, tmp_path):
    pytest.importorskip("distributed")
    out = subprocess.run(
        _cli("dataset", "build", "--out", str(tmp_path / "DS"), "--plans", str(plans),
             "--count", "1", "--scheduler", f"tcp://127.0.0.1:{_free_port()}", "--quiet"),
        env=_env(), capture_output=True, text=True, timeout=120)  # fmt: skip
    assert out.returncode == 2 and "cannot reach" in out.stderr and "Traceback" not in out.stderr


# ------------------------------------------------------------- clean, export
def test_clean_and_export(reference, tmp_path):
    import shutil

    ds = tmp_path / "DS"
    shutil.copytree(reference, ds)
    with pytest.raises(InputError, match="not been cleaned"):
        export_dataset(ds, "packed", progress=False)
    labels = tmp_path / "labels.csv"
    labels.write_text("index,label\n" + "".join(
        f"{i},{'complete' if i % 2 else 'partial'}\n" for i in range(COUNT)))  # fmt: skip
    assert read_labels(labels)["1"] == 1
    rep = clean_dataset(ds, labels)
    assert rep.n_labelled == COUNT and rep.n_complete == COUNT // 2
    assert set(rep.importances) == set(FEATURE_NAMES)
    assert (ds / "cleaner.skops").is_file() and rep.figure.is_file()
    st = dataset_status(ds)
    assert sum(st["clean"].values()) == COUNT
    model = load_cleaner(ds / "cleaner.skops")
    assert model.n_estimators == 100 and model.max_features == 11
    kept = st["clean"].get("complete", 0)
    # exports
    res = export_dataset(ds, "packed", everything=True, progress=False)
    assert res.path == ds / "packed.npz"
    pk = load_packed(res.path)
    assert pk.a.shape == (COUNT, 32, 32) and set(pk.meta["indices"]) == set(range(COUNT))
    for plan in set(pk.plan_id):
        assert len(set(pk.split[pk.plan_id == plan])) == 1  # no plan in two splits
    pix = export_dataset(ds, "pix2pix", everything=True, progress=False)
    import cv2

    img = cv2.imread(str(next(pix.path.rglob("*.png"))), cv2.IMREAD_GRAYSCALE)
    assert img.shape == (32, 64)
    fold = export_dataset(ds, "folders", everything=True, progress=False)
    a_names = sorted(p.relative_to(fold.path / "A") for p in (fold.path / "A").rglob("*.png"))
    b_names = sorted(p.relative_to(fold.path / "B") for p in (fold.path / "B").rglob("*.png"))
    assert a_names == b_names and len(a_names) == COUNT
    # the saved cleaner applies to a folder of pairs (the folders export)
    decisions = apply_cleaner(ds / "cleaner.skops", fold.path)
    assert len(decisions) == COUNT and all(0 <= d["p_complete"] <= 1 for d in decisions)
    if kept:  # by default only the pairs the cleaner kept
        assert export_dataset(ds, "folders", tmp_path / "kept", progress=False).count == kept


def test_cleaner_refuses_one_class_and_bad_labels(reference, tmp_path):
    import shutil

    ds = tmp_path / "DS"
    shutil.copytree(reference, ds)
    bad = tmp_path / "bad.csv"
    bad.write_text("index,label\n0,maybe\n")
    with pytest.raises(InputError, match="line 2"):
        clean_dataset(ds, bad)
    with pytest.raises(InputError, match="one class"):
        clean_dataset(ds, coverage_threshold=1e-9)  # every pair complete


def test_a_count_that_cannot_be_built_is_refused_before_any_work(tmp_path):
    """A huge --count was accepted and its pairs' tasks were all made up front (9.6 GB
    after 38 s for 10**12); now it is refused in one line, and tasks are made lazily."""
    out = subprocess.run(_cli("dataset", "build", "--out", str(tmp_path / "DS"), "--plans",
                              "generated", "--count", str(10**12)),
                         env=_env(), capture_output=True, text=True, timeout=120)  # fmt: skip
    assert out.returncode == 2, out.stderr
    assert out.stderr.splitlines() == [
        "map2map: error: --count: must be at most 1000000 (pairs are numbered with six "
        "digits: pairs/000000 .. pairs/999999), got 1000000000000"]
    assert not (tmp_path / "DS").exists()


def test_the_pool_draws_its_tasks_as_workers_take_them():
    from map2map.datasets.pool import run_pool

    drawn, got = [], []

    def tasks():
        for i in range(5):
            drawn.append(i)
            yield i

    def on_result(task, result, worker):
        got.append(result)
        assert len(drawn) <= len(got) + 2  # one running, one handed out ahead at most

    run_pool(tasks(), abs, 1, on_result=on_result, on_crash=lambda t, why: False,
             start_method="fork")  # fmt: skip
    assert sorted(got) == [0, 1, 2, 3, 4]


def _interrupting_task(spec):
    if spec.index == 1:
        raise KeyboardInterrupt
    return run_pair(spec)


def test_the_build_lock_is_gone_when_a_build_ends(plans, tmp_path):
    ds = tmp_path / "DS"
    build_dataset(ds, str(plans), 1, 5, PARAMS, workers=0, progress=False, figures=False)
    assert not (ds / ".build.lock").exists()  # finished
    with pytest.raises(KeyboardInterrupt):
        build_dataset(ds, str(plans), 3, 5, PARAMS, workers=0, progress=False, figures=False,
                      task=_interrupting_task)  # fmt: skip
    assert not (ds / ".build.lock").exists()  # interrupted
    assert dataset_status(ds)["counts"] == {"done": 1}


def test_the_build_lock_still_keeps_builds_apart(tmp_path, monkeypatch):
    import fcntl

    from map2map.datasets.build import _build_lock

    with _build_lock(tmp_path):
        with pytest.raises(InputError, match="another build is running"):
            with _build_lock(tmp_path):
                pass
    assert not (tmp_path / ".build.lock").exists()
    # a build that locks a file the previous one has just removed (and a third build has
    # made again) notices it holds the wrong file and locks the one in the folder
    real, calls = fcntl.flock, []

    def flock_then_replace(fh, op):
        real(fh, op)
        calls.append(fh)
        if len(calls) == 1:
            (tmp_path / ".build.lock").unlink()
            (tmp_path / ".build.lock").write_text("")

    monkeypatch.setattr(fcntl, "flock", flock_then_replace)
    with _build_lock(tmp_path):
        monkeypatch.setattr(fcntl, "flock", real)
        assert len(calls) == 2 and calls[0].closed
        assert os.fstat(calls[1].fileno()).st_ino == os.stat(tmp_path / ".build.lock").st_ino
        with pytest.raises(InputError, match="another build is running"):
            with _build_lock(tmp_path):
                pass


def test_ctrl_c_stops_a_build_cleanly(plans, tmp_path):
    """Ctrl-C (SIGINT to the whole process group) while workers are mid-pair: one line,
    exit 130, no resource_tracker "leaked semaphore" noise, no lock file left."""
    ds = tmp_path / "DS"
    # 40 pairs: the build must still be running when the signal lands (6 could all finish
    # between the first done pair and the SIGINT once SLAM got faster)
    args = _cli("dataset", "build", "--out", str(ds), "--plans", str(plans), "--count", "40",
                "--seed", "5", "--source", "both", "--duration", "30", "--size", "32",
                "--fov", "360", "--workers", "2", "--quiet", "--no-figures")  # fmt: skip
    # the build starts with Ctrl-C's default disposition, as from a terminal: a test
    # process that ignores SIGINT (some runners do) would pass SIG_IGN on to it
    def default_ctrl_c():
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    proc = subprocess.Popen(args, env=_env(), start_new_session=True, text=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            preexec_fn=default_ctrl_c)  # fmt: skip
    deadline = time.monotonic() + 60
    while proc.poll() is None and _done(ds) < 1 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert proc.poll() is None, "the build ended before it could be interrupted"
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err
    assert "leaked" not in err and "Traceback" not in err, err
    assert err.strip().splitlines()[-1] == "map2map: interrupted"
    assert not (ds / ".build.lock").exists()
    assert 1 <= _done(ds) < 40
