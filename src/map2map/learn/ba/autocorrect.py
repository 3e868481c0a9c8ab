"""``map2map autocorrect``: a SLAM map in, a CAD-like plan out, in the input's frame.

:func:`autocorrect` runs Model_BA on any map, whatever its size, resolution and origin
(``model="none"``: the same steps with a network that draws no wall, the classical
cleaning alone, :mod:`~map2map.learn.ba.correctors`):

1. the known part of the map (its content box, plus a margin that is 4 px at the
   dataset's size, as in the dataset's crop) is padded to a square with unknown cells;
   when its walls run at an angle to the grid (:func:`dominant_angle`, more than 3
   degrees, coherent; more than 6 with anchored walls, whose faces follow the map's own
   angle up to that, :data:`MIN_SKEW_ANCHORED_DEG`), the square is rotated to make them
   axis-aligned (nearest neighbour, padded so nothing is cut) -- the model learnt plans
   drawn along the axes -- and everything below is rotated back at the end
   (``meta["autocorrect"]["deskew_deg"]``);
2. that square is brought to the dataset's size (256) exactly as the dataset was made
   (:func:`map2map.maps.preprocess.square_resize`: walls survive any reduction) and then to
   the model's size by area averaging (:func:`map2map.learn.training.data.downsample_input`) --
   the same path the training inputs took;
3. the generator's output is post-processed back to the square *at the input's own
   resolution* (:func:`map2map.learn.ba.postprocess.postprocess`: upsampling, snapping to the
   three values, straight walls; by default (``anchor=True``) the input's own walls,
   straightened at full resolution on the median of their observed faces, pieces of
   one wall line put on one line, and given the plan's thickness, plus the network's
   walls the input does not show;
   ``anchor=False`` draws the network's walls, moved by at most half a model cell onto
   the input's);
4. the square is cut back into the input's grid: the result has the input's shape,
   resolution and origin, so every corrected wall lies in the same world frame. Cells
   outside the square (all unknown in the input) stay unknown.

A map up to :data:`LARGE_SHRINK` (2.5) times the dataset's size goes through the network
in one piece (resizing): the model learnt whole buildings at the dataset's scale. A larger
one (``large``, default ``"tile"`` since 2026-11-26) is cut into half-overlapping tiles of
at most :data:`TILE_SHRINK` times that size, each brought to the dataset's size and run
through the network, and the centre of each tile's output is kept
(:func:`tile_grid`, :func:`stitch_tiles`); the post-processing then runs once on the
whole map, at the tiles' scale, leaving out the network's walls that have no seen space
on one side (``open_frontiers``: a tile shows the network a piece of a building, which
it closes). ``large="resize"`` is the behaviour before, ``"refuse"`` returns such a map
uncorrected with a warning. The walls seen from one side are drawn as thick as the
training plans' walls scaled by the input's own walls (``thickness="input"``, default
since 2026-11-26: at most the shrink, see :func:`drawn_wall_px`), not by the shrink
alone, which made the walls of a real office map 15-24 px thick against the plan's 3.
Measured on the 18 real Halmstad maps and the gen1500 val split in ``git show
e59abf4^:docs/learn.md``, "Real maps beyond the training scale". A result the model is
unsure of carries a warning in ``meta["autocorrect"]["warnings"]`` (and on the
command line): content more than 4x the dataset's size corrected whole (a building much
larger than those the model learnt: walls below a model cell are lost and the layout may
be invented), or
output walls that the input's walls do not support (fewer than half of the output wall
pixels within half a wall plus 2 dataset pixels of an input wall means the network
invented structure).

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> data = np.full((90, 140), 127, np.uint8)
>>> data[10:80, 10:130] = 255; data[10, 10:130] = 0; data[79, 10:130] = 0
>>> data[10:80, 10] = 0; data[10:80, 129] = 0
>>> m = OccupancyMap(data, 0.04, (1.0, -2.0, 0.0))
>>> out = autocorrect(m)                        # the shipped weights
>>> out.shape, out.resolution, out.origin
((90, 140), 0.04, (1.0, -2.0, 0.0))
>>> sorted(out.meta["autocorrect"])
['deskew_deg', 'model', 'segments_px', 'support', 'warnings']
>>> autocorrect(m, "none").meta["autocorrect"]["model"]   # no network, no weights read
'none'
"""

from __future__ import annotations

import os
import warnings
from concurrent.futures import ThreadPoolExecutor
from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ...core.errors import InputError
from ...core.grid import OCCUPIED, UNKNOWN, OccupancyMap
from ...core.parallel import default_workers
from ...maps.preprocess import square_resize
from .correction import Correction, _world_segments
from .null import NullNetwork
from .pieces import drawn_pieces
from .postprocess import postprocess
from .squares import (
    MIN_SKEW_DEG,
    Prepared,
    cut_tiles,
    dominant_angle,
    prepare,
    rotate_square,
    stitch_tiles,
    tile_grid,
    unrotate_segments,
)

if TYPE_CHECKING:
    from .model import BAModel

__all__ = ["autocorrect", "autocorrect_many", "Correction",
           "dominant_angle", "drawn_wall_px", "tile_grid", "stitch_tiles"]

#: With anchored walls (``anchor=True``) the faces follow the map's own angle up to
#: ``ANCHOR.tilt_max_deg`` (:mod:`~map2map.learn.ba.anchor`), so only larger rotations are
#: deskewed: the
#: nearest-neighbour rotation there and back moves wall pixels (``git show
#: e59abf4^:docs/learn.md``, "Why 43 % of the maps were not improved": 28 -> 31 of 38
#: val maps improved).
MIN_SKEW_ANCHORED_DEG = 6.0
MAX_SHRINK = 4.0  # content squares more than 4x the dataset's size get a warning
#: what the shipped weights measured (docs/autocorrect.md, "The shipped weights", "Real
#: maps"), said with every correction they make
REAL_MAPS_ANCHORED = ("walls anchored on the input lowered the appendix-metric error on 192 "
                      "of 200 held-out simulated maps; on 18 real Halmstad maps against "
                      "their floor plans (the 14 large office maps corrected in tiles) it "
                      "lowered it on 11; on 2 of the office maps the output's alignment "
                      "with the plan failed the keypoint check, one of them 4.3 px worse; "
                      "against the part of the plan the robot saw, the output's walls are "
                      "no closer than the input's (boundary F1 equal, Chamfer 6.8 px "
                      "against 6.4) and drawn 2-3 times as thick as the plan's")
#: Median wall thickness (occupied area / centre-line length) of the training SLAM maps at
#: the dataset's 256 px (200 train maps of gen1500: 2.07 px, 5-95 % 1.84-2.93; their
#: plans' walls 5.61): how thick the dataset's SLAM maps draw a wall (``thickness="input"``).
SLAM_WALL_PX = 2.07
#: Default of :func:`autocorrect`'s ``thickness`` (``git show e59abf4^:docs/learn.md``,
#: "Real maps beyond the training scale": on the 18 real Halmstad maps the output's
#: alignment failed on 1 instead of 6, observed-part Chamfer 8.5 px instead of 10.2;
#: gen1500 val unchanged).
THICKNESS = "input"
#: Default of :func:`autocorrect`'s ``open_frontiers`` for maps corrected whole; maps
#: corrected in tiles (``large="tile"``) leave their frontiers open unless told otherwise
#: (a tile shows the network a piece of a building, which it closes).
OPEN_FRONTIERS = False
#: Default of :func:`autocorrect`'s ``large``: what is done with a map whose content is
#: more than :data:`LARGE_SHRINK` times the dataset's size.
LARGE = "tile"
#: Shrink (content side / dataset size) beyond which ``large`` applies: the training
#: plans reach 2.39 (docs/autocorrect.md, "Real maps").
LARGE_SHRINK = 2.5


def _weights_caveat(net: BAModel, anchor: bool) -> list[str]:
    """What the shipped weights were measured to do (weights whose note says PROVISIONAL,
    or the shipped file): a warning on every correction made with them, since a map from
    a real robot is outside what they were trained and measured on."""
    if not getattr(net, "learnt", True):          # the null network: nothing learnt
        return []
    from .model import pretrained_path

    provisional = "PROVISIONAL" in str(net.header.get("note", ""))
    try:
        shipped = Path(net.source).resolve() == pretrained_path().resolve()
    except (OSError, ValueError):
        shipped = False
    if not (provisional or shipped):
        return []
    measured = (REAL_MAPS_ANCHORED if anchor else
                "the network's own walls (no anchoring) lowered the appendix-metric "
                "error on only 10 of 81 held-out simulated maps and 2 of 18 real "
                "Halmstad maps (earlier weights)")
    what = ("provisional Model_BA weights (small CPU training run)" if provisional else
            "Model_BA weights trained on simulated SLAM maps only")
    return [f"{what}: walls the input does not show are placed only to within a few "
            f"pixels; {measured} (docs/autocorrect.md)"]


def drawn_wall_px(net: BAModel, m: OccupancyMap, shrink: float, thickness: str | float,
                  square: np.ndarray | None = None) -> float:
    """Thickness (pixels of the input) of the walls :func:`autocorrect` draws where the
    input saw a wall from one side only (two-sided walls are grown to
    ``ANCHOR.min_thick`` scaled by the same factor).

    ``thickness`` is one of:

    * ``"shrink"``: the training plans' thickness (``net.target_wall_px``, dataset
      pixels) times the shrink (content side / dataset size), as the whole map is
      resized: a building five times the training size gets walls five times as thick
      (the behaviour before 2026-11-26, 15 px on the real Halmstad maps against the
      plans' 3);
    * ``"resolution"``: the training plans' thickness in metres (at the dataset's
      resolution, ``header["dataset"]["identity"]["resolution"]``, 0.05 m/px) over the
      map's own resolution: walls do not grow with the building;
    * ``"input"``: the training thickness times the input's own wall thickness over the
      training SLAM maps' (:data:`SLAM_WALL_PX`), at least 1 and at most the shrink: the
      input's walls say how many of its pixels a dataset pixel of wall is;
    * a number: that many pixels.

    Examples
    --------
    >>> from map2map.learn.ba.model import load_model
    >>> net = load_model()
    >>> m = OccupancyMap(np.full((10, 10), 255, np.uint8), 0.025)
    >>> drawn_wall_px(net, m, 5.0, "shrink") == 5 * net.target_wall_px
    True
    >>> bool(np.isclose(drawn_wall_px(net, m, 5.0, "resolution"),
    ...                 2 * net.target_wall_px))                    # 0.05 / 0.025
    True
    >>> drawn_wall_px(net, m, 5.0, 3.0)
    3.0
    """
    t = net.target_wall_px
    if thickness == "shrink":
        return t * shrink
    if thickness == "resolution":
        ident = net.header.get("dataset", {}).get("identity", {})
        return t * float(ident.get("resolution") or 0.05) / float(m.resolution)
    if thickness == "input":
        from ...maps.preprocess import wall_thickness_px

        if shrink <= 1.0:  # the bound: no need to measure the input's walls (2 ms a map)
            return t * shrink
        t_in = wall_thickness_px(square[None]) if square is not None else SLAM_WALL_PX
        return t * min(shrink, max(1.0, t_in / SLAM_WALL_PX))
    if isinstance(thickness, str):
        raise ValueError(f"thickness: 'shrink', 'resolution', 'input' or pixels, "
                         f"not {thickness!r}")
    return float(thickness)


def autocorrect_many(maps: list[OccupancyMap], model: str | os.PathLike | BAModel | None =
                     "pretrained", *, straighten: bool = True, deskew: bool = True,
                     anchor: bool = True, device: str = "cpu", batch: int = 256,
                     workers: int | None = None, thickness: str | float | None = None,
                     open_frontiers: bool | None = None,
                     large: str | None = None) -> list[Correction]:
    """:func:`autocorrect` for several maps, the network run in batches (``model`` as
    :func:`autocorrect`'s).

    The per-map work around the network (squaring, deskewing, post-processing, the way
    back to the input's frame) runs on ``workers`` threads (default: one per CPU core, at
    most 8; OpenCV and the numba kernels release the GIL: post-processing measured 1.6x
    faster on 2 cores; the plan drawer after it,
    :class:`~map2map.learn.ba.correctors.DrawnCorrector`, uses as many processes). The
    results do not depend on ``workers``. ``thickness``, ``open_frontiers`` and ``large``
    as :func:`autocorrect` (``None``: :data:`THICKNESS`, :data:`OPEN_FRONTIERS` (True for
    a map corrected in tiles), :data:`LARGE`).
    """
    net = _network(model, device)
    if not getattr(net, "learnt", True) and not (anchor and straighten):
        raise InputError("model", "'none' is the anchored, straightened post-processing "
                                  "alone: anchor=False and straighten=False "
                                  "(--no-anchor, --no-straighten) need a network")
    thickness = THICKNESS if thickness is None else thickness
    frontiers = open_frontiers  # None: by map, whole or in tiles
    large = LARGE if large is None else large
    if large not in ("resize", "tile", "refuse"):
        raise ValueError(f"large: 'resize', 'tile' or 'refuse', not {large!r}")
    n_workers = default_workers() if workers is None else max(1, int(workers))
    with ThreadPoolExecutor(n_workers) if n_workers > 1 else nullcontext() as pool:
        run = pool.map if pool is not None else map
        min_skew = MIN_SKEW_ANCHORED_DEG if anchor and straighten else MIN_SKEW_DEG
        squares = list(run(lambda m: prepare(m, net.data_size, deskew, min_skew), maps))
        big = {i for i, s in enumerate(squares)
               if s is not None and s.side > LARGE_SHRINK * net.data_size}
        todo = [i for i, s in enumerate(squares) if s is not None
                and not (large == "refuse" and i in big)]
        # what goes through the network: per map its square, or its tiles
        pieces = {i: (cut_tiles(squares[i].model, *tile_grid(squares[i].model.shape[0],
                                                           net.data_size))
                      if large == "tile" and i in big else [squares[i].model]) for i in todo}
        flat = [(i, t) for i in todo for t in pieces[i]]
        inputs = np.stack(list(run(lambda it: square_resize(it[1], net.data_size), flat))) \
            if flat else np.zeros((0, net.data_size, net.data_size), np.uint8)
        outputs = net.predict(inputs, batch)
        out_of, k = {}, 0
        for i in todo:
            got = outputs[k:k + len(pieces[i])]
            k += len(pieces[i])
            out_of[i] = (stitch_tiles(got, tile_grid(squares[i].model.shape[0],
                                                     net.data_size)[0])
                         if large == "tile" and i in big else got[0])
        results = list(run(lambda i: _finish(maps[i], squares[i], out_of.get(i), net,
                                             straighten, anchor, thickness,
                                             _open(frontiers, i in big and large == "tile"),
                                             refused=i in big and large == "refuse",
                                             tiled=i in big and large == "tile"),
                           range(len(maps))))
    for i in (i for i, s in enumerate(squares) if s is not None):  # caller's thread, in order
        for w in results[i].warnings:
            warnings.warn(w, stacklevel=2)
    return results


def _network(model, device: str):
    """The network of ``model``: a loaded one as it is, ``"none"`` the
    :class:`~map2map.learn.ba.null.NullNetwork` (no weights read), ``"thesis"``,
    ``"pretrained"`` or None the shipped weights, else a run folder or weights file
    (``map2map autocorrect --model``'s names)."""
    if _is_network(model):
        return model
    if isinstance(model, str) and model == "none":
        return NullNetwork()
    if isinstance(model, str) and model == "thesis":
        model = "pretrained"
    from .model import load_model  # torch: only for a network

    return load_model(model, device)


def _is_network(model) -> bool:
    """``model`` is a loaded network (a :class:`BAModel`, or a stand-in with its
    ``predict``, ``size``, ``data_size``, ``target_wall_px``, ``header`` and ``source``,
    e.g. :class:`~map2map.learn.ba.null.NullNetwork`), not a name or path."""
    return hasattr(model, "predict") and hasattr(model, "target_wall_px")


def _open(open_frontiers: bool | None, tiled: bool) -> bool:
    """``open_frontiers`` for one map: as given, else on for a map corrected in tiles
    and :data:`OPEN_FRONTIERS` for one corrected whole (``git show
    e59abf4^:docs/learn.md``, "Real maps beyond the training scale": tiles without it
    invent walls in the unknown space around the building, 25-28 px observed Chamfer on
    the real maps against 6.4 for the input)."""
    if open_frontiers is not None:
        return bool(open_frontiers)
    return True if tiled else OPEN_FRONTIERS


def _finish(m: OccupancyMap, sq: Prepared | None, output: np.ndarray | None, net: BAModel,
            straighten: bool, anchor: bool, thickness: str | float = "shrink",
            open_frontiers: bool = False, refused: bool = False,
            tiled: bool = False) -> Correction:
    """One map of :func:`autocorrect_many` after the network: post-processing, back to
    the input's frame and resolution, segments in metres, warnings (not yet issued).
    With ``tiled``, ``output`` is the tiles' stitched one (``large="tile"``)."""
    if sq is None or refused:
        msg = "the map holds no known cells; nothing to correct" if sq is None else (
            f"the map is {sq.side / net.data_size:.1f}x larger than the maps the model "
            f"learnt on ({net.data_size} px; at most {LARGE_SHRINK}x is corrected with "
            "large='refuse'): returned as it is, not corrected")
        out = m.copy()
        out.meta["autocorrect"] = {"warnings": [msg], "segments_px": [], "support": None,
                                   "model": net.source, "refused": sq is not None}
        return Correction(out, np.zeros((0, 4)), [msg])
    square, row0, col0, side = sq.square.data, sq.square.row0, sq.square.col0, sq.side
    angle, pad, model_sq = sq.angle, sq.pad, sq.model
    n = model_sq.shape[0]
    scale = n / net.data_size
    wall_px = max(1.0, drawn_wall_px(net, m, scale, thickness, square))
    thick_px = scale if thickness == "shrink" else wall_px / net.target_wall_px
    frame, guide = n, model_sq
    if tiled:  # stitched tiles: their frame, at their scale
        count, stride = tile_grid(n, net.data_size)
        frame = (count + 1) * stride
        guide = np.full((frame, frame), UNKNOWN, np.uint8)
        guide[:n, :n] = model_sq
        scale = 2 * stride / net.data_size
    data_sq, segs = postprocess(output, (frame, frame), guide, wall_px=wall_px,
                                straighten=straighten, anchor=anchor, data_px=scale,
                                thick_px=thick_px,
                                open_frontiers=open_frontiers)
    data_sq = data_sq[:n, :n]
    if angle:  # back from the deskewed frame
        data_sq = rotate_square(data_sq, -angle)[pad:pad + side, pad:pad + side]
        segs = unrotate_segments(segs, angle, n) - pad
    H, W = m.shape
    data = np.full((H, W), UNKNOWN, np.uint8)
    rs, re = max(0, row0), min(H, row0 + side)
    cs, ce = max(0, col0), min(W, col0 + side)
    data[rs:re, cs:ce] = data_sq[rs - row0:re - row0, cs - col0:ce - col0]
    # segments: square pixel indices -> input pixel indices, kept where they lie on the
    # walls drawn there (rotated back and cut to the input's grid, a wall may lose its
    # pixels beyond the grid, or a thin one a pixel), -> continuous input coordinates
    seg_px = segs + np.array([col0, row0, col0, row0])
    seg_px = drawn_pieces(seg_px, data == OCCUPIED) + 0.5
    warns = []
    if side / net.data_size > MAX_SHRINK and not tiled and getattr(net, "learnt", True):
        warns.append(f"the map is {side / net.data_size:.1f}x larger than the maps the "
                     "model learnt on "
                     f"({net.data_size} px): small walls may be lost and the layout "
                     "invented; check the figure, or correct parts of the map separately")
    plan_px = max(1.0, net.target_wall_px * side / net.data_size)  # the training walls'
    support = _support(square, data_sq, tol=0.5 * plan_px + 2 * side / net.data_size)
    if support is not None and support < 0.5:
        warns.append(f"only {support:.0%} of the output's wall pixels lie near a wall of "
                     "the input: the model may have invented structure; check the figure")
    warns += _weights_caveat(net, anchor)
    out = m.copy(data=data)
    out.meta["autocorrect"] = {"model": net.source, "warnings": warns,
                               "support": support, "segments_px": seg_px.tolist(),
                               "deskew_deg": angle}
    if tiled:
        out.meta["autocorrect"]["tiles"] = tile_grid(n, net.data_size)[0] ** 2
    return Correction(out, _world_segments(m, seg_px), warns)


def _support(inp: np.ndarray, out: np.ndarray, tol: float) -> float | None:
    """Share of output wall pixels within ``tol`` pixels of an input wall pixel."""
    ow = out == OCCUPIED
    iw = inp == OCCUPIED
    if not ow.any():
        return None
    if not iw.any():
        return 0.0
    import cv2

    dist = cv2.distanceTransform((~iw).astype(np.uint8), cv2.DIST_L2, 5)
    return float((dist[ow] <= tol).mean())


def autocorrect(m: OccupancyMap, model: str | os.PathLike | BAModel | None = "pretrained",
                *, straighten: bool = True, deskew: bool = True, anchor: bool = True,
                device: str = "cpu", thickness: str | float | None = None,
                open_frontiers: bool | None = None, large: str | None = None) -> OccupancyMap:
    """Auto-correct a SLAM map into a CAD-like plan with Model_BA (module docstring).

    Parameters
    ----------
    m : OccupancyMap
        The SLAM map (any size, resolution, origin).
    model : "thesis", "none", run folder, weights file, BAModel or NullNetwork
        Which Model_BA to use: ``"thesis"`` (or ``"pretrained"``, None) the shipped
        weights; ``"none"`` (or a :class:`~map2map.learn.ba.null.NullNetwork`) no
        network, the anchored post-processing alone, which needs ``anchor`` and
        ``straighten`` (``map2map autocorrect --model none``).
    straighten : bool
        Post-processing steps 3-5 (straight walls); False keeps the snapped upsampling.
    deskew : bool
        Rotate maps whose walls are not along the grid to the axes first (step 1).
    anchor : bool
        Walls anchored on the input's observed wall faces at full resolution (step 3,
        default); False places them where the network's low-resolution output says.
    device : str
        Torch device for the network.
    thickness : "shrink", "resolution", "input" or float, optional
        How thick the walls seen from one side are drawn (:func:`drawn_wall_px`);
        default :data:`THICKNESS`.
    open_frontiers : bool, optional
        Leave out the network's walls at the edge of the input's known area or beyond it
        (:func:`map2map.learn.ba.postprocess.frontier_walls`: on a partial map the edge of
        what the robot saw is not a wall); default :data:`OPEN_FRONTIERS`, and on for a
        map corrected in tiles.
    large : "resize", "tile" or "refuse", optional
        A map whose content is more than :data:`LARGE_SHRINK` x the dataset's size:
        resized whole to it (the network sees the building at a scale it never learnt),
        corrected in half-overlapping tiles of at most :data:`TILE_SHRINK` x that size,
        the centre of each tile's output kept (:func:`tile_grid`, :func:`stitch_tiles`),
        or returned uncorrected with a warning; default :data:`LARGE`.

    Returns
    -------
    OccupancyMap
        Same shape, resolution and origin as ``m``; ``meta["autocorrect"]`` holds the
        wall segments (input pixels), the wall support and any warnings.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = autocorrect_many([m], model, straighten=straighten, deskew=deskew,
                               anchor=anchor, device=device, thickness=thickness,
                               open_frontiers=open_frontiers, large=large)[0]
    for w in res.warnings:
        warnings.warn(w, stacklevel=2)
    return res.map


