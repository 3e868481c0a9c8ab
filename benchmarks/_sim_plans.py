"""Plans for the simulator benchmarks: procedural apartments and HouseExpo (shared data)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap  # noqa: E402

SHARED = Path(
    os.environ.get("MAP2MAP_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
)
HOUSEEXPO = SHARED / "houseexpo"


def block_reduce(m: OccupancyMap, f: int) -> OccupancyMap:
    """Coarsen by ``f`` keeping thin walls: a block is occupied if any pixel is,
    else free if most pixels are free, else unknown."""
    h, w = (m.height // f) * f, (m.width // f) * f
    d = m.data[m.height - h :, :w].reshape(h // f, f, w // f, f)
    occ = (d == OCCUPIED).any(axis=(1, 3))
    free = (d == FREE).mean(axis=(1, 3)) > 0.5
    out = np.full(occ.shape, UNKNOWN, np.uint8)
    out[free] = FREE
    out[occ] = OCCUPIED
    return OccupancyMap(out, m.resolution * f, m.origin)


def houseexpo_json() -> list[tuple[str, OccupancyMap]]:
    from map2map.maps.formats import load_map

    return [(p.stem[:8], load_map(p)) for p in sorted((HOUSEEXPO / "json").glob("*.json"))]


def houseexpo_renders(n: int) -> list[tuple[str, OccupancyMap]]:
    """The first ``n`` renders (1 cm/px), cropped and reduced to 0.05 m/px."""
    from map2map.maps.formats import load_map

    out = []
    for p in sorted((HOUSEEXPO / "renders").glob("*.png"))[:n]:
        m = load_map(p, resolution=0.01)
        r0, r1, c0, c1 = m.content_bbox()
        m = m.crop(r0 - 10, r1 + 10, c0 - 10, c1 + 10)
        out.append((p.stem[:8], block_reduce(m, 5)))
    return out


def apartments(n: int, seed0: int = 0) -> list[tuple[str, OccupancyMap]]:
    from map2map.maps.floorplan import generate_floorplan

    return [(f"apt{s}", generate_floorplan(s, kind="apartment")) for s in range(seed0, seed0 + n)]
