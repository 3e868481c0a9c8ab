"""Where a dataset's CAD plans come from: generated, HouseExpo files, or ROS/image maps.

A plan source is described by a small, JSON-serialisable :class:`PlanSource` (it travels
to worker processes and Dask workers) and resolved to a plan by :func:`load_plan`, a
pure function of the source and the plan index, so that every worker sees the same plan.

Generated plans (``--plans generated``)
---------------------------------------
The thesis (sec. 4.1) trained on HouseExpo. The procedural plans of
:func:`map2map.maps.floorplan.generate_floorplan` are drawn with a HouseExpo-like mix of
sizes, measured on the 80 HouseExpo renders of the shared data (1 cm/px, bounding box of
the known pixels):

==================  =====  =====  ======  =====  =====
percentile             5     25     50      75     95
==================  =====  =====  ======  =====  =====
long side (m)        6.9   10.6   13.9    19.6   30.0
short side (m)       5.4    7.5   10.4    12.9   18.9
free area (m^2)       31     59    118     180    331
==================  =====  =====  ======  =====  =====

so the long side is log-normal with median 13.9 m and log-sigma 0.45 (5-95 %:
6.7-29 m), clipped to [6, 30] m, and the short side is the long side times an aspect
drawn uniformly in [0.5, 1.0] (renders: median 0.75), at least 5 m. One plan in five is
an office (corridor spine) when its long side exceeds 12 m, the rest apartments; rooms
follow from the size (the generator's rule). HouseExpo's two JSON plans here have 4 and 7
rooms; generated plans of the median size have 7-11 (corridors and halls count as
rooms), so room counts run somewhat higher than HouseExpo's, sizes match.

Plan ``j`` of a generated source with seed ``S`` is drawn from
``SeedSequence(S, spawn_key=(1, j))``: it depends on ``(S, j)`` only.

Folders
-------
A folder of HouseExpo JSON files, HouseExpo renders or ROS/image maps (every file
:func:`map2map.maps.formats.load_map` reads; ``.yaml`` preferred over the ``.pgm`` it
names) is listed in sorted name order; plan ``j`` is file ``j mod n`` (a plan gets one
hypothesis per pass). Pictures take ``plan_resolution`` (HouseExpo renders: 0.01 m/px);
plans finer than the working ``resolution`` (0.05 m/px) are reduced to it keeping
one-pixel walls, and every plan is cropped to its content plus a small unknown margin.

Examples
--------
>>> src = PlanSource("generated")
>>> pid, plan = load_plan(src, seed=0, index=3)
>>> pid, plan.resolution
('gen-0-000003', 0.05)
>>> load_plan(src, seed=0, index=3)[1] == plan
True
"""

from __future__ import annotations

import hashlib
import math
import os
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from ..core.errors import InputError
from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap

__all__ = [
    "PlanSource",
    "GENERATED",
    "list_plan_files",
    "plan_sizes",
    "load_plan",
    "reduce_resolution",
    "source_digest",
]

GENERATED = "generated"
#: Log-normal long side (metres) fitted to the HouseExpo renders: median, log-sigma, clip.
LONG_MEDIAN_M, LONG_LOG_SIGMA, LONG_CLIP_M = 13.9, 0.45, (6.0, 30.0)
#: Short side = long side x U(ASPECT), at least SHORT_MIN_M.
ASPECT, SHORT_MIN_M = (0.5, 1.0), 5.0
#: Probability that a plan with a long side above OFFICE_MIN_M is an office.
OFFICE_SHARE, OFFICE_MIN_M = 0.2, 12.0
#: Unknown margin (metres) kept around a folder plan's content.
MARGIN_M = 0.3
_PLAN_SUFFIXES = (".json", ".yaml", ".yml", ".png", ".pgm", ".jpg", ".jpeg", ".tif", ".tiff")


@dataclass(frozen=True)
class PlanSource:
    """Where plans come from.

    Parameters
    ----------
    kind : str
        ``"generated"`` or a folder path.
    resolution : float
        Working resolution (metres per pixel) of every plan.
    plan_resolution : float, optional
        Metres per pixel of picture plans (default: stored in the file, else 0.05).
    files : tuple of str
        For a folder: the plan files (names relative to it), in order.
    """

    kind: str
    resolution: float = 0.05
    plan_resolution: float | None = None
    files: tuple[str, ...] = ()

    @classmethod
    def from_arg(cls, value: str, resolution: float = 0.05,
                 plan_resolution: float | None = None) -> PlanSource:  # fmt: skip
        """The source named on the command line (``generated`` or a folder).

        Raises :class:`InputError` for a missing folder or one without plans.
        """
        if not (math.isfinite(resolution) and 0.01 <= resolution <= 0.25):
            raise InputError("resolution", f"must be in [0.01, 0.25] m/px, got {resolution}")
        if value == GENERATED:
            return cls(GENERATED, float(resolution), None, ())
        folder = Path(value)
        if not folder.is_dir():
            raise InputError(folder, "plans must be 'generated' or a folder of plan files")
        files = list_plan_files(folder)
        if not files:
            raise InputError(folder, f"no plan files ({', '.join(_PLAN_SUFFIXES)}) in the folder")
        return cls(str(folder.resolve()), float(resolution), plan_resolution, tuple(files))

    @property
    def generated(self) -> bool:
        return self.kind == GENERATED

    def only(self, index: int) -> PlanSource:
        """This source reduced to the one file plan ``index`` uses (a generated source as
        it is): what a pair's task carries to a worker, instead of the whole file list
        (35,000 names for HouseExpo). :func:`load_plan` gives the same plan from both.

        Examples
        --------
        >>> src = PlanSource("/plans", files=("a.json", "b.json", "c.json"))
        >>> src.only(4).files
        ('b.json',)
        """
        if self.generated or not self.files:
            return self
        return replace(self, files=(self.files[int(index) % len(self.files)],))

    def as_dict(self) -> dict:
        d = asdict(self)
        d["files"] = len(self.files)
        return d


def list_plan_files(folder: str | os.PathLike) -> list[str]:
    """Plan files of ``folder`` in sorted order (a ``.pgm``/``.png`` named by a yaml beside
    it is left out: the yaml stands for it).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> for n in ("b.yaml", "b.pgm", "a.json", "notes.txt"):
    ...     _ = (d / n).write_text("image: b.pgm\\n" if n == "b.yaml" else "")
    >>> list_plan_files(d)
    ['a.json', 'b.yaml']
    """
    folder = Path(folder)
    names = sorted(p.name for p in folder.iterdir()
                   if p.is_file() and p.suffix.lower() in _PLAN_SUFFIXES)  # fmt: skip
    named = set()
    for n in names:
        if n.lower().endswith((".yaml", ".yml")):
            try:
                import yaml

                doc = yaml.safe_load((folder / n).read_text())
                if isinstance(doc, dict) and isinstance(doc.get("image"), str):
                    named.add(Path(doc["image"]).name)
            except Exception:  # an unreadable yaml is still a plan (it will fail as one)
                pass
    return [n for n in names if n not in named]


def source_digest(src: PlanSource) -> str:
    """SHA-256 over a folder's plan names and sizes (a changed folder is a new dataset)."""
    h = hashlib.sha256(src.kind.encode())
    for name in src.files:
        p = Path(src.kind) / name
        size = p.stat().st_size if p.exists() else -1
        h.update(f"\n{name}\t{size}".encode())
    return h.hexdigest()


def plan_sizes(rng: np.random.Generator) -> tuple[str, tuple[float, float]]:
    """Draw a HouseExpo-like (kind, (W, H) metres) for a generated plan.

    Examples
    --------
    >>> kind, (w, h) = plan_sizes(np.random.default_rng(0))
    >>> kind in ("apartment", "office") and 5.0 <= min(w, h) and max(w, h) <= 30.0
    True
    """
    long = float(np.clip(LONG_MEDIAN_M * math.exp(LONG_LOG_SIGMA * rng.standard_normal()),
                         *LONG_CLIP_M))  # fmt: skip
    short = max(SHORT_MIN_M, long * float(rng.uniform(*ASPECT)))
    office = long > OFFICE_MIN_M and rng.random() < OFFICE_SHARE
    if rng.random() < 0.5:
        long, short = short, long
    return ("office" if office else "apartment"), (round(long, 2), round(short, 2))


def reduce_resolution(m: OccupancyMap, resolution: float) -> OccupancyMap:
    """Coarsen ``m`` to about ``resolution`` m/px by an integer factor, keeping thin walls
    (a block with any occupied pixel is occupied, else free if most pixels are free).

    Examples
    --------
    >>> d = np.full((20, 20), 255, np.uint8); d[:, 7] = 0
    >>> r = reduce_resolution(OccupancyMap(d, 0.01), 0.05)
    >>> r.shape, r.resolution, int((r.data == 0).sum())
    ((4, 4), 0.05, 4)
    """
    f = int(round(resolution / m.resolution))
    if f <= 1:
        return m
    h, w = (m.height // f) * f, (m.width // f) * f
    d = m.data[m.height - h :, :w].reshape(h // f, f, w // f, f)
    occ = (d == OCCUPIED).any(axis=(1, 3))
    free = (d == FREE).mean(axis=(1, 3)) > 0.5
    out = np.full(occ.shape, UNKNOWN, np.uint8)
    out[free] = FREE
    out[occ] = OCCUPIED
    return OccupancyMap(out, m.resolution * f, m.origin, dict(m.meta))


def _crop_margin(m: OccupancyMap) -> OccupancyMap:
    box = m.content_bbox()
    if box is None:
        return m
    k = max(2, int(round(MARGIN_M / m.resolution)))
    r0, r1, c0, c1 = box
    out = m.crop(max(0, r0 - k), min(m.height, r1 + k), max(0, c0 - k), min(m.width, c1 + k))
    return out.pad(top=max(0, k - r0), bottom=max(0, r1 + k - m.height),
                   left=max(0, k - c0), right=max(0, c1 + k - m.width))  # fmt: skip


def load_plan(src: PlanSource, seed: int, index: int) -> tuple[str, OccupancyMap]:
    """Plan ``index`` of ``src``: ``(plan id, plan)``, a pure function of its arguments.

    Raises
    ------
    InputError
        The plan file is unreadable (naming it).
    """
    if src.generated:
        from ..maps.floorplan import generate_floorplan

        rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(1, int(index))))
        kind, size = plan_sizes(rng)
        plan = generate_floorplan(rng, kind=kind, size=size, resolution=src.resolution)
        plan.meta.update(kind=kind)
        return f"gen-{int(seed)}-{int(index):06d}", plan
    from ..maps.formats import load_map

    name = src.files[int(index) % len(src.files)]
    path = Path(src.kind) / name
    res = src.plan_resolution if path.suffix.lower() not in (".yaml", ".yml") else None
    plan = load_map(path, resolution=res)
    if plan.resolution < src.resolution * 0.99:
        plan = reduce_resolution(plan, src.resolution)
    plan = _crop_margin(plan)
    plan.meta = {"file": name}
    return Path(name).stem, plan
