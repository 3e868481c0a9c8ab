"""Map formats: speed of every reader/writer and the HouseExpo thin-wall accuracy.

Run: ``python3 -m benchmarks.bench_formats``. Uses ``../shared/data`` (or
``$MAP2MAP_SHARED_DATA``) when present for the real-data parts; the synthetic parts
run anywhere. Prints one line per figure.
"""

from __future__ import annotations

import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy import ndimage as ndi
from skimage.graph import MCP_Geometric

from map2map.core.grid import OccupancyMap
from map2map.maps.formats import load_map, save_map
from map2map.maps.houseexpo import load_houseexpo

HERE = Path(__file__).resolve().parent
SHARED = Path(os.environ.get("MAP2MAP_SHARED_DATA", HERE.parent.parent / "shared" / "data"))


def timed(fn, *args, repeat=3, **kwargs):
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn(*args, **kwargs)
        best = min(best, time.perf_counter() - t0)
    return best, out


def bench_ros_and_pictures(tmp: Path) -> None:
    rng = np.random.default_rng(0)
    data = np.full((4000, 4000), 255, np.uint8)
    data[rng.random(data.shape) < 0.1] = 0
    data[:, :500] = 127
    m = OccupancyMap(data, 0.05, (-10.0, -20.0, 0.1))
    for name in ("map.yaml", "map.png", "map.pgm"):
        path = tmp / name
        t_save, _ = timed(save_map, m, path)
        t_load, back = timed(load_map, path)
        assert back == m
        mpx = m.data.size / 1e6
        print(
            f"{name:10s} 4000x4000: save {t_save * 1e3:7.1f} ms ({mpx / t_save:6.1f} Mpx/s), "
            f"load {t_load * 1e3:7.1f} ms ({mpx / t_load:6.1f} Mpx/s), round trip exact"
        )


def bench_renders() -> None:
    renders = sorted((SHARED / "houseexpo" / "renders").glob("*.png"))[:20]
    if not renders:
        print("houseexpo renders: shared data absent, skipped")
        return
    t0 = time.perf_counter()
    mismatched = 0
    for path in renders:
        m = load_map(path, resolution=0.01)
        import cv2

        raw = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        expect = np.where(raw == 255, 255, np.where(raw == 0, 0, 127)).astype(np.uint8)
        mismatched += int((m.data != expect).sum())
    dt = time.perf_counter() - t0
    print(
        f"houseexpo renders: {len(renders)} pictures of 3746x3268 read in {dt:.1f} s "
        f"({dt / len(renders) * 1e3:.0f} ms each incl. check); cells off 255/0/128: {mismatched}"
    )


def geodesic(m, rc):
    d, _ = MCP_Geometric(np.where(m.free, 1.0, np.inf)).find_costs([tuple(int(v) for v in rc)])
    return d * m.resolution


def bench_houseexpo() -> None:
    files = sorted((SHARED / "houseexpo" / "json").glob("*.json"))
    if not files:
        print("houseexpo json: shared data absent, skipped")
        return
    for path in files:
        for res in (0.01, 0.05):
            t, m = timed(load_houseexpo, path, resolution=res)
            print(f"houseexpo {path.stem[:8]} at {res * 100:g} cm: {m.shape}, {t * 1e3:.0f} ms")
        fine = load_houseexpo(path, resolution=0.01)
        coarse = load_houseexpo(path, resolution=0.05)
        plain = load_houseexpo(path, resolution=0.05)
        from map2map.maps.houseexpo import rasterise_houseexpo

        plain = rasterise_houseexpo(json.loads(path.read_text()), thin_walls=False)
        rr, cc = np.nonzero(coarse.free)
        x, y = coarse.pixel_to_world(rr, cc)
        r1, c1 = fine.world_to_pixel(x, y)
        inner = np.argwhere(ndi.distance_transform_edt(coarse.free) >= 3)
        seeds = inner[np.random.default_rng(0).choice(len(inner), 5, replace=False)]
        worst_short, worst_detour = 0.0, 0.0
        for seed in seeds:
            sx, sy = coarse.pixel_to_world(*seed)
            d1 = geodesic(fine, fine.world_to_pixel(sx, sy))[r1, c1]
            d5 = geodesic(coarse, seed)[rr, cc]
            ok = np.isfinite(d1) & fine.free[r1, c1]
            worst_short = max(worst_short, float(np.max(d1[ok] - d5[ok])))
            worst_detour = max(worst_detour, float(np.max(d5[ok] - d1[ok])))
        wall_edge = fine.occupied & ndi.binary_dilation(fine.free, np.ones((3, 3), bool))
        er, ec = np.nonzero(wall_edge)
        x, y = fine.pixel_to_world(er, ec)
        r5, c5 = coarse.world_to_pixel(x, y)
        near = ndi.binary_dilation(coarse.occupied, np.ones((3, 3), bool))[r5, c5].mean()
        extra = int((coarse.occupied & ~plain.occupied).sum())
        print(
            f"houseexpo {path.stem[:8]} 1 cm vs 5 cm: wall pixels kept within 1 px "
            f"{near * 100:.2f}%, geodesic shortcut max {worst_short:.3f} m (hole if >> 0), "
            f"detour max {worst_detour:.3f} m; thin-wall pixels added over plain fill: {extra}"
        )


def bench_dxf(tmp: Path) -> None:
    import ezdxf

    rng = np.random.default_rng(0)
    for n, furniture in ((20, 0), (50, 2)):
        doc = ezdxf.new(units=4)
        msp = doc.modelspace()
        # n x n rooms of 4 x 3 m, each with a 0.9 m door and its swing, single-line walls,
        # and some furniture outlines
        for i in range(n):
            for j in range(n):
                x0, y0 = i * 4000, j * 3000
                msp.add_line((x0, y0), (x0 + 1500, y0))
                msp.add_line((x0 + 2400, y0), (x0 + 4000, y0))
                msp.add_line((x0, y0), (x0, y0 + 3000))
                msp.add_arc((x0 + 1500, y0), 900, 0, 90)
                for _ in range(furniture):
                    x, y = x0 + rng.uniform(300, 3000), y0 + rng.uniform(300, 2000)
                    box = [(x, y), (x + 600, y), (x + 600, y + 600), (x, y + 600)]
                    msp.add_lwpolyline(box, close=True)
        msp.add_line((0, n * 3000), (n * 4000, n * 3000))
        msp.add_line((n * 4000, 0), (n * 4000, n * 3000))
        path = tmp / f"grid{n}.dxf"
        doc.saveas(path)
        t, m = timed(load_map, path, repeat=1)
        print(
            f"dxf {n * n} rooms ({len(msp)} entities, {n * 4} x {n * 3} m) at 5 cm: "
            f"{m.shape}, {t:.2f} s, free {m.free.sum() * 0.0025:.0f} m²"
        )


def bench_dxf_export(tmp: Path) -> None:
    """Generated plans -> DXF drawing -> map: cells that change (walls and free space)."""
    try:
        from map2map.maps.floorplan import generate_floorplan
    except ImportError:
        print("dxf export: map2map.maps.floorplan not available, skipped")
        return
    from map2map.maps.dxf import load_dxf, save_dxf

    changed, cells, t_save, t_load = 0, 0, 0.0, 0.0
    for seed in range(5):
        for kind in ("apartment", "office"):
            a = generate_floorplan(seed, kind=kind, furniture=True)
            t0 = time.perf_counter()
            save_dxf(a, tmp / "plan.dxf")
            t1 = time.perf_counter()
            b = load_dxf(tmp / "plan.dxf")
            t_save, t_load = t_save + t1 - t0, t_load + time.perf_counter() - t1
            r, c = (int(v) for v in b.world_to_pixel(*a.pixel_to_world(0, 0)))
            window = b.data[r : r + a.height, c : c + a.width]
            changed += int((window != a.data).sum())
            cells += a.data.size
    print(
        f"dxf export: 10 generated plans (furniture) -> .dxf -> map: {changed} of {cells} "
        f"cells changed; save {t_save / 10 * 1e3:.0f} ms, load {t_load / 10 * 1e3:.0f} ms each"
    )


def main() -> None:
    print("(timings on a shared machine: noisy)")
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        bench_ros_and_pictures(tmp)
        bench_dxf(tmp)
        bench_dxf_export(tmp)
    bench_houseexpo()
    bench_renders()


if __name__ == "__main__":
    main()
