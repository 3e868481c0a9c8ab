"""Procedural floor plans and thesis 4.1 preprocessing: speed and validity.

Targets: ``generate_floorplan`` under 0.2 s for a 30 x 20 m plan at 0.05 m/px;
every plan one connected, fully reachable free space for a 0.2 m robot.

Run: ``python3 -m benchmarks.bench_plans`` (prints a table; numbers depend on
machine load).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from map2map.core.grid import OccupancyMap
from map2map.maps.floorplan import connectivity, generate_floorplan
from map2map.maps.preprocess import harmonise, preprocess

RENDERS = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "houseexpo" / "renders"


def timed(fn, repeats: int) -> tuple[float, float]:
    """(median, max) seconds of ``repeats`` calls."""
    times = []
    for i in range(repeats):
        t0 = time.perf_counter()
        fn(i)
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), float(np.max(times))


def main() -> None:
    generate_floorplan(0)  # warm imports
    print("generate_floorplan (median / max over seeds, s):")
    rows = [
        ("office 30x20 m, 0.05 m/px", dict(kind="office", size=(30, 20))),
        ("office 30x20 m, furniture", dict(kind="office", size=(30, 20), furniture=True)),
        ("apartment 12x9 m", dict(kind="apartment", size=(12, 9))),
        ("apartment random size, furniture", dict(kind="apartment", furniture=True)),
        ("office random size", dict(kind="office")),
        ("office 30x20 m, 0.02 m/px", dict(kind="office", size=(30, 20), resolution=0.02)),
    ]
    for name, kw in rows:
        med, mx = timed(lambda i, kw=kw: generate_floorplan(i, **kw), 20)
        print(f"  {name:<36s} {med:7.4f} / {mx:7.4f}   target < 0.2 s")

    n, bad, rooms, doors = 300, 0, [], []
    t0 = time.perf_counter()
    for seed in range(n):
        kind = ("apartment", "office")[seed % 2]
        m = generate_floorplan(seed, kind=kind, furniture=seed % 3 == 0)
        bad += not connectivity(m).ok
        rooms.append(sum(r["kind"] == "room" for r in m.meta["rooms"]))
        doors += [d["width"] for d in m.meta["doors"]]
    print(
        f"validity over {n} random plans ({time.perf_counter() - t0:.1f} s): "
        f"{bad} failing the 0.2 m robot rule; rooms per plan {min(rooms)}-{max(rooms)} "
        f"(mean {np.mean(rooms):.1f}); door widths {min(doors):.2f}-{max(doors):.2f} m"
    )

    plan = generate_floorplan(1, kind="office", size=(30, 20))
    med, _ = timed(lambda i: preprocess(plan, 256, thicken=1, crop=True), 10)
    print(f"preprocess 30x20 m plan ({plan.shape[1]}x{plan.shape[0]}) -> 256: {med:.4f} s")
    renders = sorted(RENDERS.glob("*.png"))[:5]
    if renders:
        from PIL import Image

        ts = []
        for path in renders:
            img = np.asarray(Image.open(path))
            t0 = time.perf_counter()
            preprocess(OccupancyMap(harmonise(img), 0.01), 256, thicken=1, crop=True)
            ts.append(time.perf_counter() - t0)
        print(
            f"preprocess HouseExpo render {img.shape[1]}x{img.shape[0]} (1 cm/px) -> 256: "
            f"median {np.median(ts):.3f} s over {len(ts)} renders"
        )
    else:
        print("HouseExpo renders not found: skipped the real-data preprocessing timing")


if __name__ == "__main__":
    main()
