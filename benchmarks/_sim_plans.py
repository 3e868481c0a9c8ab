"""Plans for the simulator benchmarks: procedural apartments and HouseExpo (shared data).

Imported by the ``bench_sim*``/``bench_slam`` benchmarks as ``benchmarks._sim_plans``
(run them from the repository root: ``python3 -m benchmarks.bench_sim``).
"""

from __future__ import annotations

import os
from pathlib import Path

from map2map.core.grid import OccupancyMap
from map2map.datasets.plans import reduce_resolution

SHARED = Path(
    os.environ.get("MAP2MAP_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
)
HOUSEEXPO = SHARED / "houseexpo"


def houseexpo_json() -> list[tuple[str, OccupancyMap]]:
    from map2map.maps.formats import load_map

    return [(p.stem[:8], load_map(p)) for p in sorted((HOUSEEXPO / "json").glob("*.json"))]


def houseexpo_renders(n: int) -> list[tuple[str, OccupancyMap]]:
    """The first ``n`` renders (1 cm/px), cropped and reduced to 0.05 m/px
    (:func:`map2map.datasets.plans.reduce_resolution`: thin walls kept)."""
    from map2map.maps.formats import load_map

    out = []
    for p in sorted((HOUSEEXPO / "renders").glob("*.png"))[:n]:
        m = load_map(p, resolution=0.01)
        r0, r1, c0, c1 = m.content_bbox()
        m = m.crop(r0 - 10, r1 + 10, c0 - 10, c1 + 10)
        out.append((p.stem[:8], reduce_resolution(m, 0.05)))
    return out


def apartments(n: int, seed0: int = 0) -> list[tuple[str, OccupancyMap]]:
    from map2map.maps.floorplan import generate_floorplan

    return [(f"apt{s}", generate_floorplan(s, kind="apartment")) for s in range(seed0, seed0 + n)]
