"""Campus-scale SLAM memory: peak RSS and seconds of ``map2map slam`` on a generated campus log.

Target (issue #35, item 2): every Radish log maps at the default resolution (0.05 m)
within 4 GiB. The largest, freiburg-campus, is about 300 m x 250 m of outdoor campus
driven along a ~1.8 km path with an 80 m SICK scanner. This benchmark generates a log
of that scale -- no data is copied: buildings, hedges and trees on a 300 m x 250 m
campus, a robot driving a 1.9 km route through its streets at 1 m/s with five 180-beam
scans a second (80 m range, no-returns beyond), odometry with 1 % scale error and a
heading drift of 0.02 deg per metre -- writes it as a CARMEN log, and runs ``map2map
slam`` on it once per backend, each in a fresh process, reporting its peak resident
memory (``getrusage`` of the child), its seconds, the map's size and the memory
estimate ``map2map slam`` checks before it starts
(:func:`map2map.slam.offline.memory_estimate`).

The graph backend spends its time on each keyframe's likelihood lookup tables, which
span the last ten keyframes' 80 m readings (a 160 m square at 2.5 cm, rebuilt per
keyframe: 0.2-0.5 s each); the benchmark takes a keyframe every 2 m instead of 0.5 m
(``--graph-keyframes``) to stay within ten minutes. Its memory is the map's tiles and one
lookup table, neither of which depends on the keyframe spacing.

Usage::

    python -m benchmarks.slam_memory               # the campus (1.9 km), both backends
    python -m benchmarks.slam_memory --scale 0.3   # a smaller campus, for a quick look
    python -m benchmarks.slam_memory --backend rbpf --particles 30
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

LIMIT_GIB = 4.0

#: Run in the child: ``map2map slam``'s steps (read, estimate, map, write), then its peak RSS.
CHILD = """
import json, resource, sys, time
from map2map.jobs.slam import write_slam_outputs
from map2map.robotlog.logs import load_log
from map2map.slam.offline import backend_options, memory_estimate, run_slam
log_path, out, backend, particles, options = sys.argv[1:6]
particles = int(particles) if particles != "-" else None
options = json.loads(options)
t0 = time.perf_counter()
log = load_log(log_path)
opts = backend_options(log, backend, particles=particles, **options)
est = memory_estimate(log, backend, **opts)
res = run_slam(log, backend, particles=particles, **options)
write_slam_outputs(res, out)
sec = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"seconds": sec, "peak_rss": peak, "estimate": est,
                  "map": list(res.map.shape), "tiles": res.mapper.memory_bytes()}))
"""


# ----------------------------------------------------------------------------- the campus
def campus(scale: float = 1.0, seed: int = 0):
    """Boxes ``(K, 4)`` = ``xmin, ymin, xmax, ymax`` of a campus, and the route's waypoints.

    Streets run along x = 10, 80, 150, 220, 290 m and y = 10, 90, 170, 240 m (times
    ``scale``); each block between them holds one to three buildings 5-7 m from the
    streets' centre lines, trees (0.6 m) line the streets every 12-18 m, a hedge
    closes the campus.
    """
    rng = np.random.default_rng(seed)
    xs = np.array([10.0, 80.0, 150.0, 220.0, 290.0]) * scale
    ys = np.array([10.0, 90.0, 170.0, 240.0]) * scale
    boxes = []
    for i in range(len(xs) - 1):
        for j in range(len(ys) - 1):
            x0, x1 = xs[i] + 5, xs[i + 1] - 5
            y0, y1 = ys[j] + 5, ys[j + 1] - 5
            if x1 - x0 < 4 or y1 - y0 < 4:
                continue
            n = int(rng.integers(1, 4))
            cuts = np.sort(rng.uniform(x0, x1, n - 1))
            edges = np.concatenate([[x0], cuts, [x1]])
            for a, b in zip(edges[:-1], edges[1:], strict=True):
                if b - a < 3:
                    continue
                inset = rng.uniform(0, 2, 4)
                boxes.append((a + inset[0], y0 + inset[1], b - 1.5 - inset[2], y1 - inset[3]))
    # trees along every street, 3 m off its centre line, alternating sides
    for x in xs:
        for k, y in enumerate(np.arange(ys[0] + 6, ys[-1] - 6, rng.uniform(12, 18))):
            cx = x + (3 if k % 2 else -3)
            boxes.append((cx - 0.3, y - 0.3, cx + 0.3, y + 0.3))
    for y in ys:
        for k, x in enumerate(np.arange(xs[0] + 6, xs[-1] - 6, rng.uniform(12, 18))):
            cy = y + (3 if k % 2 else -3)
            boxes.append((x - 0.3, cy - 0.3, x + 0.3, cy + 0.3))
    # the outer edge: a hedge around the campus
    x0, x1, y0, y1 = xs[0] - 6, xs[-1] + 6, ys[0] - 6, ys[-1] + 6
    boxes += [
        (x0, y0, x1, y0 + 1),
        (x0, y1 - 1, x1, y1),
        (x0, y0, x0 + 1, y1),
        (x1 - 1, y0, x1, y1),
    ]
    route = [(xs[0], ys[0]), (xs[-1], ys[0]), (xs[-1], ys[-1]), (xs[0], ys[-1]), (xs[0], ys[0])]
    for i in range(1, len(xs) - 1):  # up and down the inner streets
        route += [(xs[i], ys[0]), (xs[i], ys[-1])] if i % 2 else [(xs[i], ys[-1]), (xs[i], ys[0])]
    return np.asarray(boxes, float), route


def cast(boxes, pose, angles, max_range):
    """Ranges from ``pose`` along ``angles`` to the nearest box (``inf``: nothing in range)."""
    x, y, th = pose
    near = (
        (boxes[:, 2] > x - max_range)
        & (boxes[:, 0] < x + max_range)
        & (boxes[:, 3] > y - max_range)
        & (boxes[:, 1] < y + max_range)
    )
    b = boxes[near]
    a = th + angles
    dx, dy = np.cos(a)[:, None], np.sin(a)[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        tx0, tx1 = (b[None, :, 0] - x) / dx, (b[None, :, 2] - x) / dx
        ty0, ty1 = (b[None, :, 1] - y) / dy, (b[None, :, 3] - y) / dy
    tmin = np.maximum(np.minimum(tx0, tx1), np.minimum(ty0, ty1))
    tmax = np.minimum(np.maximum(tx0, tx1), np.maximum(ty0, ty1))
    t = np.where((tmax >= tmin) & (tmin > 0), tmin, np.inf).min(1, initial=np.inf)
    return np.where(t < max_range, t, np.inf)


def write_campus_log(path, scale: float = 1.0, seed: int = 0) -> dict:
    """Write the campus run as a CARMEN log; returns its path length, extent and scan count."""
    from map2map.robotlog.base import LaserScan, OdometryReading
    from map2map.robotlog.carmen import write_carmen
    from map2map.trajectory.timing import time_waypoints

    rng = np.random.default_rng(seed)
    boxes, route = campus(scale, seed)
    # the true path: turn in place, then drive, through the route's corners
    tr = time_waypoints(np.asarray(route, float), v_max=1.0, omega_max=0.5, dt=0.2)
    truth = np.column_stack([tr.x, tr.y, tr.theta])
    angles = np.deg2rad(np.arange(-90.0, 90.0, 1.0))
    # odometry: 1 % scale error, heading drift of 0.02 deg per metre, small noise
    step = np.diff(truth, axis=0)
    c, s = np.cos(truth[:-1, 2]), np.sin(truth[:-1, 2])
    fwd = c * step[:, 0] + s * step[:, 1]
    dth = (step[:, 2] + math.pi) % (2 * math.pi) - math.pi
    fwd_o = fwd * 1.01 + rng.normal(0, 0.002, fwd.size)
    dth_o = dth * 1.005 + np.deg2rad(0.02) * fwd + rng.normal(0, 0.0005, fwd.size)
    odo = np.zeros_like(truth)
    odo[0] = truth[0]
    for k in range(fwd.size):  # integrate
        th = odo[k, 2]
        odo[k + 1] = (odo[k, 0] + fwd_o[k] * math.cos(th), odo[k, 1] + fwd_o[k] * math.sin(th),
                      th + dth_o[k])  # fmt: skip
    records = []
    for k, pose in enumerate(truth):
        r = cast(boxes, pose, angles, 80.0)
        r = np.where(np.isfinite(r), r + rng.normal(0, 0.02, r.size), np.inf)
        t = float(tr.t[k])
        scan = LaserScan(t, r.astype(np.float32), float(angles[0]), math.radians(1.0), 0.0, 80.0)
        records.append((OdometryReading(t, *odo[k]), scan, None))
    write_carmen(path, records)
    length = float(np.hypot(*np.diff(truth[:, :2], axis=0).T).sum())
    span = truth[:, :2].max(0) - truth[:, :2].min(0)
    return {"path_m": length, "span_m": span.tolist(), "scans": len(records)}


def run_child(log: Path, backend: str, particles: int | None, out: Path, options: dict) -> dict:
    """One ``map2map slam`` run in a fresh process: seconds, peak RSS, estimate, map size."""
    opts = json.dumps(options)
    cmd = [sys.executable, "-c", CHILD, str(log), str(out), backend, str(particles or "-"), opts]
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        return {"error": (done.stderr.strip().splitlines() or ["?"])[-1]}
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scale", type=float, default=1.0, help="campus size factor (default 1)")
    ap.add_argument("--backend", choices=["rbpf", "graph", "both"], default="both")
    ap.add_argument("--particles", type=int, default=None,
                    help="rbpf particles (default: map2map slam's for a recorded log, 20)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--graph-keyframes",
        type=float,
        default=2.0,
        metavar="M",
        help="graph: a keyframe every M metres (default 2; the backend's own 0.5 takes about "
        "four times as long, each keyframe building 80 m lookup tables, for the same map)",
    )
    args = ap.parse_args(argv)
    backends = ["rbpf", "graph"] if args.backend == "both" else [args.backend]
    ok = True
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "campus.log.gz"
        t0 = time.perf_counter()
        info = write_campus_log(log, args.scale, args.seed)
        print(
            f"campus log: {info['path_m'] / 1000:.2f} km path, "
            f"{info['span_m'][0]:.0f} m x {info['span_m'][1]:.0f} m driven, "
            f"{info['scans']} scans of 180 beams (80 m), generated in "
            f"{time.perf_counter() - t0:.0f} s"
        )
        print(f"{'backend':8} {'seconds':>8} {'peak RSS':>10} {'estimate':>10} "
              f"{'tiles':>9} {'map (px)':>13}")  # fmt: skip
        for backend in backends:
            opts = {"min_travel_distance": args.graph_keyframes, "min_time_interval": -1.0}
            opts = opts if backend == "graph" else {}
            r = run_child(log, backend, args.particles, Path(tmp) / f"out-{backend}", opts)
            if "error" in r:
                print(f"{backend:8} failed: {r['error']}")
                ok = False
                continue
            gib = r["peak_rss"] / 2**30
            ok &= gib <= LIMIT_GIB
            h, w = r["map"]
            print(
                f"{backend:8} {r['seconds']:8.0f} {gib:8.2f} GiB {r['estimate'] / 2**30:6.2f} GiB "
                f"{r['tiles'] / 2**20:6.0f} MiB {h:>6} x {w:<6}"
            )
    print(f"target: peak RSS <= {LIMIT_GIB:.0f} GiB per backend: {'met' if ok else 'NOT met'}")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
