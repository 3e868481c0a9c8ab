"""Reader of the Halmstad map-alignment data (sensor maps, layouts, annotated keypoints).

The data (GPL-3.0, not shipped) holds, per environment (E5, HIH), sensor maps
``maps/<ENV>/pseudo_occupancy/<ENV>_NN.png`` (0/127/255), one anti-aliased RGBA
layout ``maps/<ENV>/layout/<ENV>_layout.png``, keypoints
``annotations/keypoints_<name>.npy`` with a LOWER-LEFT origin, and associations
``annotations/association_<A>_<B>.npy`` (rows ``i, j``: keypoint ``i`` of A is
keypoint ``j`` of B; some rows are ``None``). It is the yardstick of the alignment:
an alignment is scored by the residual of the associated keypoints mapped through
it, and the least-squares similarity fitted to the keypoints themselves is the
floor of any global transform.

Examples
--------
>>> import numpy as np
>>> src = np.array([[0.0, 0.0], [10, 0], [0, 10], [10, 10], [5, 5]])
>>> dst = src * 2 + 3
>>> dst[4] += 40                                    # one wrong association
>>> T, inliers = robust_similarity(src, dst)
>>> inliers.tolist()
[True, True, True, True, False]
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
from PIL import Image

from ..core.geometry import apply, decompose_similarity, fit_similarity
from ..core.grid import OccupancyMap, ternarize

__all__ = [
    "load_halmstad",
    "load_keypoints",
    "load_association",
    "halmstad_pairs",
    "robust_similarity",
    "keypoint_residuals",
    "annotated_scale",
    "map_path",
]

#: placeholder resolution: the data gives none (E5 sensor maps are ~0.8 x the layout's scale,
#: HIH ones ~1.16 x; :func:`annotated_scale`)
HALMSTAD_RESOLUTION = 0.05


def _env(name: str) -> str:
    return name.split("_")[0]


def _map_path(root: Path, name: str) -> Path:
    env = _env(name)
    if name.endswith("layout"):
        return root / "maps" / env / "layout" / f"{name}.png"
    return root / "maps" / env / "pseudo_occupancy" / f"{name}.png"


def map_path(root: str | Path, name: str) -> Path:
    """The picture of a sensor map (``E5_01``) or layout (``E5_layout``)."""
    return _map_path(Path(root), name)


def load_halmstad(root: str | Path, name: str) -> OccupancyMap:
    """A sensor map (``E5_01``) or layout (``E5_layout``) as an :class:`OccupancyMap`.

    The RGBA layout is thresholded (about 128 unknown, 255 free, 0 wall).

    Parameters
    ----------
    root : path-like
        The data folder (``$HALMSTAD_ROOT``).
    name : str
        Map name.

    Returns
    -------
    OccupancyMap
    """
    path = _map_path(Path(root), name)
    img = np.asarray(Image.open(path))
    if img.ndim == 3:
        img = img[..., 0]
    data = ternarize(img, occupied_below=64, free_above=191)
    return OccupancyMap(data, HALMSTAD_RESOLUTION, meta={"source": str(path), "name": name})


def load_keypoints(root: str | Path, name: str, height: int) -> np.ndarray:
    """(N, 2) keypoints of a map in this package's pixel frame (origin top-left).

    Parameters
    ----------
    root : path-like
        The data folder.
    name : str
        Map name.
    height : int
        The map's height in pixels (the file's y axis points up).

    Returns
    -------
    (N, 2) float array
        ``(x, y)`` pixels, y down.
    """
    k = np.load(Path(root) / "annotations" / f"keypoints_{name}.npy").astype(float)
    return np.column_stack([k[:, 0], height - k[:, 1]])


def load_association(root: str | Path, a: str, b: str) -> np.ndarray:
    """(K, 2) int index pairs (row of A's keypoints, row of B's), ``None`` rows dropped.

    Parameters
    ----------
    root : path-like
        The data folder.
    a, b : str
        Map names.

    Returns
    -------
    (K, 2) int array
    """
    raw = np.load(Path(root) / "annotations" / f"association_{a}_{b}.npy", allow_pickle=True)
    rows = [r for r in raw if r is not None and all(v is not None for v in r)]
    return np.array(rows, dtype=np.int64).reshape(-1, 2)


def halmstad_pairs(root: str | Path, *, both_ways: bool = True) -> Iterator[tuple[str, str]]:
    """(source, target) names: every sensor map to its layout (and back with ``both_ways``).

    Parameters
    ----------
    root : path-like
        The data folder.
    both_ways : bool
        Also yield (layout, sensor map).

    Yields
    ------
    (str, str)
    """
    root = Path(root)
    for env in ("E5", "HIH"):
        for p in sorted((root / "maps" / env / "pseudo_occupancy").glob(f"{env}_*.png")):
            yield p.stem, f"{env}_layout"
            if both_ways:
                yield f"{env}_layout", p.stem


def robust_similarity(
    src: np.ndarray, dst: np.ndarray, *, rounds: int = 3, factor: float = 3.0, min_px: float = 10.0
) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares similarity with outlier rejection (residual > max(factor x median, min_px)).

    Parameters
    ----------
    src, dst : (N, 2) float arrays
        Corresponding points, N >= 3.
    rounds : int
        Refits at most.
    factor : float
        Outlier threshold as a multiple of the inliers' median residual.
    min_px : float
        Threshold floor, pixels.

    Returns
    -------
    T : (3, 3) array
        The similarity ``src -> dst``.
    inliers : (N,) bool array

    Examples
    --------
    >>> src = np.array([[0.0, 0.0], [10, 0], [0, 10], [10, 10], [5, 5]])
    >>> dst = src + 2.0; dst[4] += 40
    >>> T, inl = robust_similarity(src, dst)
    >>> inl.tolist(), T[:2, 2].round(6).tolist()
    ([True, True, True, True, False], [2.0, 2.0])
    """
    inl = np.ones(len(src), bool)
    T = fit_similarity(src, dst)
    for _ in range(rounds):
        T = fit_similarity(src[inl], dst[inl])
        res = np.hypot(*(apply(T, src) - dst).T)
        new = res <= max(factor * np.median(res[inl]), min_px)
        if new.sum() < 3 or np.array_equal(new, inl):
            break
        inl = new
    return T, inl


def keypoint_residuals(
    root, src_name: str, tgt_name: str, src: OccupancyMap, tgt: OccupancyMap, mapper
) -> tuple[float, float, float]:
    """(floor, similarity, nonrigid) mean keypoint residuals in target pixels.

    ``mapper(points) -> (similarity_points, nonrigid_points)`` maps source pixels to
    target pixels. Residuals are averaged over the inliers of the robust floor fit.

    Parameters
    ----------
    root : path-like
        The data folder.
    src_name, tgt_name : str
        Map names.
    src, tgt : OccupancyMap
        The maps as loaded by :func:`load_halmstad`.
    mapper : callable
        Source pixels -> (similarity, nonrigid) target pixels.

    Returns
    -------
    floor, similarity, nonrigid : float
        Mean residuals in target pixels: the best similarity of the keypoints
        themselves (the floor), then the two mappings.
    """
    assoc = load_association(root, src_name, tgt_name)
    ks = load_keypoints(root, src_name, src.height)[assoc[:, 0]]
    kt = load_keypoints(root, tgt_name, tgt.height)[assoc[:, 1]]
    T, inl = robust_similarity(ks, kt)
    floor = float(np.hypot(*(apply(T, ks[inl]) - kt[inl]).T).mean())
    sim, nonrigid = mapper(ks[inl])
    return (
        floor,
        float(np.hypot(*(sim - kt[inl]).T).mean()),
        float(np.hypot(*(nonrigid - kt[inl]).T).mean()),
    )


def annotated_scale(root: str | Path, env: str) -> float:
    """Median scale of the keypoint similarities of a building's sensor maps to its layout.

    The data gives no resolution. Every sensor map of a building was made by the
    same robot, so one ratio of resolutions (layout pixels per sensor-map pixel)
    holds for all of them: the median over the building's sensor maps of the scale
    of the robust similarity fitted to their annotated keypoints (E5: 0.823 over 14
    maps, spread 0.808-0.837; HIH: 1.160 over 4, 1.144-1.170). Telling an alignment
    the sensor maps' resolution is ``HALMSTAD_RESOLUTION * annotated_scale`` and the
    layout's ``HALMSTAD_RESOLUTION`` is the honest form of "the resolutions are
    known" for this data.

    Parameters
    ----------
    root : path-like
        The data folder.
    env : str
        ``"E5"`` or ``"HIH"``.

    Returns
    -------
    float
        Layout pixels per sensor-map pixel.
    """
    scales = []
    for src_name, tgt_name in halmstad_pairs(root, both_ways=False):
        if _env(src_name) != env:
            continue
        assoc = load_association(root, src_name, tgt_name)
        h = {n: Image.open(_map_path(Path(root), n)).size[1] for n in (src_name, tgt_name)}
        ks = load_keypoints(root, src_name, h[src_name])[assoc[:, 0]]
        kt = load_keypoints(root, tgt_name, h[tgt_name])[assoc[:, 1]]
        scales.append(decompose_similarity(robust_similarity(ks, kt)[0])[0])
    if not scales:
        raise ValueError(f"no sensor maps of {env!r} under {root}")
    return float(np.median(scales))
