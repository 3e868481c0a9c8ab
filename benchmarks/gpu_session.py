"""The one GPU call of a session: the throughput figures of issues #14/#15 and the
thesis-scale training runs, fitted into a fixed device-time budget.

A lent GPU comes with minutes, not hours, so everything runs in one prepared call and
each part is capped by a wall-clock budget:

0. ``graph``: the eq. 3.2 step eager against the same step as one CUDA graph replay
   (``bench_learn.py --steps-at ... --graph --check-graph``;
   :class:`map2map.learn.training.static_step.StaticStep`) for Model_32 at batch 32 / 256 / 1024
   and Model_64 at 16 / 256: first 8 steps both ways from the same weights (loss and
   weight differences, a zero learning rate reaching the graph), then the rates; which
   step ran is recorded (a failed capture falls back to eager and says so);
1. the eq. 3.2 training-step rate of Model_BA (``bench_learn.py --steps-at``) at Table
   5.1's batch and larger ones, and of Model_prog per stage (``bench_ab.py``) at Table
   5.1's batches and at ``--ab-batch-rate``;
2. ``map2map train ba`` on ``--data`` (64 px, default widths, batch ``--ba-batch``) for as
   many epochs (at most the thesis's 534) as the measured rate fits into ``--ba-seconds``;
   with ``--cuda-graph`` when part 0 captured a graph (or ``--ba-graph yes``), the step
   mode of its last epoch recorded;
3. ``map2map train ab`` (growth full, G 16-128 channels: <= 10 MB in fp16) with Table
   5.2's four stages, each given a share of ``--ab-seconds`` and as many epochs as its
   measured rate fits;
4. inference maps/s at 256 px on the GPU (``bench_learn.py --inference-only``);
5. the run folders (without the optimiser checkpoints) packed as ``ba.tar`` / ``ab.tar``.

``--parts abprobe`` (before part 3): Model_prog's 256 px step, graphed, at ``--ab-batch``
in channels-last and in NCHW, then the faster layout at twice the batch (the issue's 700
img/s); part 3 then trains in the faster layout (``train ab --nchw`` when NCHW wins by
more than 3 %).

Every training run is stopped by SIGINT at its budget plus a margin (the trainer then
writes its checkpoint), so a slower machine gives fewer epochs, never a lost call.

    python3 -m benchmarks.gpu_session --data packed.npz --out OUTDIR [--device cuda]
        [--ba-seconds 150] [--ab-seconds 200] [--deadline 560] [--quick]
        [--skip graph,bench,ba,ab,infer] [--parts abprof] [--ba-graph auto|yes|no]

Session 12 ran ``--skip bench,ab,infer --ba-batch 256 --ba-seconds 300 --deadline 460``
(H200: graphs captured, 283 BA epochs in 282 s; docs/autocorrect.md, "Measured on a GPU: the
graph, and the kernel that held the step"). The next call (the thesis's 534 epochs fit
since the upsampling fix; run it on an H100 too):

    python3 -m benchmarks.gpu_session --data .gpu/packed.npz --out $OUT/s13
        --skip bench,ab,infer --ba-batch 256 --ba-seconds 330 --deadline 470

Session 24 (H200, 2026-11-27) ran Table 5.2's schedule at 256 px on the 1,471 pairs
(stopped by its budget after 170 of 205 epochs, 65 at 256 px; docs/synthesize.md, "256 px
weights from a GPU"):

    python3 -m benchmarks.gpu_session --data .gpu/packed.npz --out /tmp/s24
        --skip graph,bench,ba,infer --parts abprobe --ab-graph yes --ab-batch 64
        --ab-schedule 32:15,64:30,128:60,256:100 --ab-seconds 400 --deadline 540

``--quick``: tiny budgets and networks, for checking the script on a CPU.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tarfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
THESIS_BA_EPOCHS = 534  # the epoch the thesis chose for Model_BA
# `map2map train` alone: the full CLI also registers the map commands, which import
# shapely/ezdxf, absent on the GPU machine
# (this checkout's src/ first on PYTHONPATH, set by _run: the code under test, whatever
# else is installed)
CLI_TRAIN = ("import argparse, sys; "
             "from map2map.cli import train as t; "
             "p = argparse.ArgumentParser(); t.register(p.add_subparsers()); "
             "a = p.parse_args(sys.argv[1:]); sys.exit(a.func(a))")
AB_SHARES = {32: 0.1, 64: 0.15, 128: 0.25, 256: 0.5}  # of --ab-seconds per stage


def _run(cmd: list[str], limit: float, log, signal: str = "TERM") -> tuple[int, str]:
    """Run ``cmd`` under ``timeout`` (``signal`` at ``limit`` s), echo and return output."""
    full = ["timeout", "-s", signal, "-k", "30", str(int(limit))] + cmd
    print("$ " + " ".join(cmd), file=log, flush=True)
    t0 = time.perf_counter()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT / "src"), *filter(None, [os.environ.get("PYTHONPATH")])]))
    p = subprocess.run(full, capture_output=True, text=True, cwd=ROOT, env=env)
    out = p.stdout + p.stderr
    print(out[-6000:], file=log, flush=True)
    print(f"[rc {p.returncode}, {time.perf_counter() - t0:.0f} s]", file=log, flush=True)
    return p.returncode, out


def _rates(text: str, pattern: str) -> dict:
    return {tuple(int(g) for g in m.groups()[:-1]): float(m.groups()[-1])
            for m in re.finditer(pattern, text, re.M)}


def _train_pairs(data: Path) -> int:
    meta = json.loads(str(np.load(data)["meta"]))
    return int(meta["splits"]["train"])


def _last_epoch(log_csv: Path, prefix: str) -> dict:
    """Epochs done, img/s and step mode (graph/eager/fallback) of a run's last logged
    epoch."""
    import csv

    if not log_csv.is_file():
        return {}
    rows = list(csv.DictReader(log_csv.open()))
    if not rows:
        return {}
    last = rows[-1]
    return {f"{prefix}_epochs_done": int(last["epoch"]),
            f"{prefix}_img_per_s": float(last.get("img_per_s") or "nan"),
            f"{prefix}_step_mode": last.get("step", "eager (no --cuda-graph)")}


def _pack(run: Path, dest: Path) -> None:
    """The run folder without its optimiser checkpoint, with the last 4 sample grids."""
    if not run.is_dir():
        return
    grids = sorted((run / "samples").glob("*.png"))[-4:]
    with tarfile.open(dest, "w") as tar:
        for f in sorted(run.iterdir()):
            if f.is_file() and f.name != "last.safetensors":
                tar.add(f, arcname=f"{run.name}/{f.name}")
        for f in grids:
            tar.add(f, arcname=f"{run.name}/samples/{f.name}")


def _stage_rates(log_csv: Path) -> dict:
    """Per stage resolution of a ``train ab`` run: epochs logged and the median img/s."""
    import csv

    if not log_csv.is_file():
        return {}
    by: dict[str, list[float]] = {}
    for row in csv.DictReader(log_csv.open()):
        by.setdefault(row.get("resolution", "?"), []).append(float(row.get("img_per_s") or "nan"))
    return {r: {"epochs": len(v), "median_img_per_s": float(np.median(v))} for r, v in by.items()}


def _probe_256(args, py: str, log, res: dict) -> bool:
    """Model_prog's graphed 256 px step in both layouts at ``--ab-batch`` (64 if unset), then
    the faster one at twice the batch; ``res["abprobe"]``; True when NCHW wins by > 3 %."""
    b = args.ab_batch or 64
    base = [py, "-m", "benchmarks.bench_ab", "--device", args.device, "--only",
            "32" if args.quick else "256", "--g-channels", "16", "--g-max-channels", "128",
            "--steps", "2" if args.quick else "10", "--graph", *(["--quick"] if args.quick else [])]
    pat = r"^\s*\d+\s+\d+\s+\d+\s+([\d.]+)\s+[\d.]+ min\s+(\S.*)$"
    probe = res.setdefault("abprobe", {})

    def one(layout: list[str], batch: int, name: str) -> float:
        _, txt = _run(base + ["--batch", str(batch)] + layout, 90, log)
        m = re.search(pat, txt, re.M)
        probe[name] = f"{m.group(1)} img/s ({m.group(2)})" if m else "failed"
        return float(m.group(1)) if m else 0.0

    cl = one([], b, f"channels_last, batch {b}")
    nchw = one(["--nchw"], b, f"nchw, batch {b}")
    use_nchw = nchw > 1.03 * cl
    lay = ["--nchw"] if use_nchw else []
    one(lay, 2 * b, f"{'nchw' if use_nchw else 'channels_last'}, batch {2 * b}")
    probe["train_layout"] = "nchw" if use_nchw else "channels_last"
    return use_nchw


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True, type=Path, help="packed.npz")
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--device", default="cuda")
    ap.add_argument("--ba-seconds", type=float, default=150.0)
    ap.add_argument("--ab-seconds", type=float, default=200.0)
    ap.add_argument("--ba-batch", type=int, default=64)
    ap.add_argument("--ab-batch-rate", type=float, default=4.0)
    ap.add_argument("--ab-batch", type=int, help="train ab with this batch at every stage "
                    "(instead of --ab-batch-rate x Table 5.1's)")
    ap.add_argument("--deadline", type=float, default=560.0,
                    help="seconds for the whole script: the training budgets shrink to fit")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--skip", default="", help="comma list of parts to skip: "
                    "graph,bench,ba,ab,infer")
    ap.add_argument("--parts", default="", help="comma list of optional parts to run: "
                    "abprof,abprobe")
    ap.add_argument("--ba-graph", choices=("auto", "yes", "no"), default="auto",
                    help="train ba with --cuda-graph: auto = when part 0 captured one")
    ap.add_argument("--ab-graph", choices=("auto", "yes", "no"), default="no",
                    help="train ab with --cuda-graph (part 1 then measures Model_prog's "
                    "graphed rates, which fit its epochs); auto = when part 0 captured one")
    ap.add_argument("--ab-schedule", help="train ab with this RES:EPOCHS schedule as is "
                    "(default: Table 5.2's stages fitted into --ab-seconds)")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    skip = set(filter(None, args.skip.split(",")))
    py = sys.executable
    log = open(args.out / "log.txt", "a")
    t_all = time.perf_counter()
    n_train = _train_pairs(args.data)
    print(f"train pairs {n_train}; device {args.device}", file=log, flush=True)
    _run([py, "-c", "import torch; print(torch.__version__, torch.cuda.is_available() and "
          "torch.cuda.get_device_name())"], 60, log)
    res = {"n_train": n_train}

    # 0. eager against CUDA-graph steps
    graph_rates, graph_ok = {}, False
    if "graph" not in skip:
        at = "32:32,32:256,32:1024,64:16,64:256" if not args.quick else "32:8,64:8"
        _, txt = _run([py, "-m", "benchmarks.bench_learn", "--device", args.device, "--steps-at",
                       at, "--graph", "--check-graph", "--seconds",
                       "2" if not args.quick else "0.5"], 240, log)
        res["graph_checks"] = re.findall(r"^graph check, (.*)$", txt, re.M)
        for m in re.finditer(r"Model_(\d+) default widths, batch (\d+)(, CUDA graph \(([^)]*)\))?"
                             r": (\d+) img/s", txt):
            key = f"{m.group(1)}:{m.group(2)}"
            slot = graph_rates.setdefault(key, {})
            if m.group(3):
                slot["graph"], slot["mode"] = float(m.group(5)), m.group(4)
                graph_ok = graph_ok or m.group(4) == "graph"
            else:
                slot["eager"] = float(m.group(5))
    res["graph_rates"] = graph_rates
    res["graph_captured"] = graph_ok
    print(json.dumps(res), file=log, flush=True)

    # 1. training-step rates
    ba_rates, ab_rates = {}, {}
    if "bench" not in skip:
        at = "32:32,32:256,32:1024,64:16,64:64,64:256" if not args.quick else "32:8,64:8"
        _, txt = _run([py, "-m", "benchmarks.bench_learn", "--device", args.device, "--steps-at",
                       at, "--seconds", "2" if not args.quick else "0.5"], 100, log)
        ba_rates = _rates(txt, r"Model_(\d+) default widths, batch (\d+): (\d+) img/s")
        q = ["--quick"] if args.quick else []
        _run([py, "-m", "benchmarks.bench_ab", "--device", args.device, "--steps", "6",
              *q], 90, log)
        g = ["--graph"] if args.ab_graph == "yes" or (args.ab_graph == "auto" and graph_ok) \
            else []
        _, t2 = _run([py, "-m", "benchmarks.bench_ab", "--device", args.device, "--steps", "6",
                      "--batch-rate", str(args.ab_batch_rate), "--g-channels", "16",
                      "--g-max-channels", "128", *g, *q], 120, log)
        ab_rates = {k[0]: v for k, v in
                    _rates(t2, r"^\s*(\d+)\s+(\d+)\s+\d+\s+([\d.]+)").items()}
    res["ba_rates"] = {f"{k[0]}:{k[1]}": v for k, v in ba_rates.items()}
    res["ab_rates"] = ab_rates
    print(json.dumps(res), file=log, flush=True)

    def left(reserve: float) -> float:
        return args.deadline - (time.perf_counter() - t_all) - reserve

    # 2. Model_BA at 64 px
    if "ba" not in skip:
        reserve = (min(args.ab_seconds, 120) + 90 if "ab" not in skip else 0) + \
            (60 if "infer" not in skip else 10)
        budget = max(10.0, min(args.ba_seconds, left(reserve)))
        res["ba_budget_s"] = budget
        use_graph = args.ba_graph == "yes" or (args.ba_graph == "auto" and graph_ok)
        res["ba_cuda_graph"] = use_graph
        # the measured rate (graphed when the run is); else H200 figures of 2026-11-26
        # (eager: session 10; graphed, with the upsampling fix: session 12)
        measured = graph_rates.get(f"64:{args.ba_batch}", {})
        known = {16: 1342.0, 256: 7275.0} if use_graph else {16: 233.0, 64: 1017.0,
                                                              256: 3129.0}
        rate = (measured.get("graph") if use_graph else measured.get("eager")) or \
            (None if use_graph else ba_rates.get((64, args.ba_batch))) or \
            known.get(args.ba_batch, 1000.0)
        epochs = int(max(2, min(THESIS_BA_EPOCHS, 0.8 * budget * rate / n_train)))
        every = max(1, epochs // 20)
        cmd = [py, "-c", CLI_TRAIN, "train", "ba", "--data", str(args.data), "--out",
               str(args.out / "ba_run"), "--epochs", str(epochs), "--batch", str(args.ba_batch),
               "--device", args.device, "--seed", "0", "--save-every", str(every), "--quiet"]
        if args.quick:
            cmd += ["--g-channels", "8", "--g-max-channels", "16", "--d-channels", "8"]
        if use_graph:
            cmd += ["--cuda-graph"]
        res["ba_cmd"] = " ".join(cmd[1:])
        rc, _ = _run(cmd, budget * 1.15 + 25, log, signal="INT")
        res["ba_rc"] = rc
        res.update(_last_epoch(args.out / "ba_run" / "log.csv", "ba"))
        _pack(args.out / "ba_run", args.out / "ba.tar")

    parts = set(filter(None, args.parts.split(",")))
    ab_nchw = False
    if "abprobe" in parts:
        ab_nchw = _probe_256(args, py, log, res)
        print(json.dumps(res), file=log, flush=True)

    # 3. Model_AB, Table 5.2's stages fitted into the budget
    if "ab" not in skip:
        budget = max(10.0, min(args.ab_seconds, left(40 if "infer" in skip else 100)))
        res["ab_budget_s"] = budget
        sched = []
        for r, share in AB_SHARES.items():
            rate = ab_rates.get(r) or {32: 3195, 64: 1131, 128: 557, 256: 158}[r]
            sched.append(f"{r}:{max(1, int(0.75 * share * budget * rate / n_train))}")
        if args.quick:
            sched = sched[:2]
        if args.ab_schedule:
            sched = [s.strip() for s in args.ab_schedule.split(",")]
        total = sum(int(s.split(":")[1]) for s in sched)
        batch = ["--batch", str(args.ab_batch)] if args.ab_batch else \
            ["--batch-rate", str(args.ab_batch_rate)]
        cmd = [py, "-c", CLI_TRAIN, "train", "ab", "--data", str(args.data), "--out",
               str(args.out / "ab_run"), "--schedule", ",".join(sched), *batch,
               "--g-channels", "16", "--g-max-channels", "128",
               "--device", args.device, "--seed", "0", "--save-every",
               str(max(1, total // 20)), "--quiet"]
        if ab_nchw:
            cmd += ["--nchw"]
        if args.quick:
            cmd += ["--d-channels", "8", "--g-max-channels", "32"]
        if args.ab_graph == "yes" or (args.ab_graph == "auto" and graph_ok):
            cmd += ["--cuda-graph"]
        res["ab_cmd"] = " ".join(cmd[1:])
        rc, _ = _run(cmd, budget + 20, log, signal="INT")
        res["ab_rc"] = rc
        res["ab_stages"] = _stage_rates(args.out / "ab_run" / "log.csv")
        res.update(_last_epoch(args.out / "ab_run" / "log.csv", "ab"))
        _pack(args.out / "ab_run", args.out / "ab.tar")

    # 4b. where Model_prog's 256 px step goes
    if "abprof" in parts:
        base = [py, "-m", "benchmarks.bench_ab", "--device", args.device, "--only",
                "32" if args.quick else "256", "--batch", "8" if args.quick else "64",
                "--g-channels", "16", "--g-max-channels", "128", "--steps",
                "2" if args.quick else "10", "--profile"]
        for extra in (["--graph"], ["--graph", "--nchw"], ["--compile"]):
            if left(20) < 60:
                break
            _, t3 = _run(base + extra, min(150, left(20)), log)
            m = re.search(r"^\s*\d+\s+\d+\s+\d+\s+([\d.]+)\s+[\d.]+ min\s+(\S.*)$", t3, re.M)
            if m:
                res.setdefault("abprof", {})[" ".join(extra)] = f"{m.group(1)} img/s ({m.group(2)})"

    # 4. inference at 256 px
    if "infer" not in skip:
        _run([py, "-m", "benchmarks.bench_learn", "--device", args.device, "--inference-only",
              "--maps", "64" if args.quick else "512", "--repeat", "2"], 120, log)
    res["seconds"] = time.perf_counter() - t_all
    (args.out / "result.json").write_text(json.dumps(res, indent=1))
    print(json.dumps(res), file=log, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
