"""The correctors ``map2map autocorrect --model`` chooses between (issue #32): the same
pipeline (:mod:`~map2map.learn.ba.autocorrect`: content square, deskew, post-processing,
back to the input's frame) with or without a network inside.

* :class:`NullCorrector` (``none``): the classical cleaning alone. The anchored
  post-processing (:func:`~map2map.learn.ba.postprocess.postprocess`, step 4b) runs with
  :class:`NullNetwork` in the network's place, an output that draws no wall and calls
  everything free: the input's own walls straightened on the median of their faces,
  pieces of one wall line put on one line, two-sided walls grown to the plan's
  thickness, free specks made unknown, and every input wall pixel that no straight wall
  explains dropped as clutter (the network keeps those it draws a wall near). No
  weights are read: it runs where the shipped file is missing or unreadable.
* :class:`ThesisCorrector` (``thesis``, and any weights file or training run): the
  thesis's Model_BA, Model_32 (the generator of eqs. 3.1-3.7) followed by the same
  post-processing; ``"pretrained"`` is the shipped weights.

Both follow the protocol of :class:`map2map.jobs.autocorrect.Corrector`: a ``name``,
a ``source`` and ``correct_many(maps, **options) -> list[OccupancyMap]``, each output
in its input's frame with ``meta["autocorrect"]`` (wall segments, warnings, ``model``);
``options`` are those of :func:`~map2map.learn.ba.autocorrect.autocorrect_many`.
Measured side by side by ``python -m map2map.experiments.table53 --models none thesis``.

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> data = np.full((90, 140), 127, np.uint8)
>>> data[10:80, 10:130] = 255; data[10, 10:130] = 0; data[79, 10:130] = 0
>>> data[10:80, 10] = 0; data[10:80, 129] = 0
>>> out = NullCorrector().correct_many([OccupancyMap(data, 0.05)])[0]
>>> out.shape, out.meta["autocorrect"]["model"]
((90, 140), 'none')
"""

from __future__ import annotations

import os

import numpy as np

from ...core.grid import OccupancyMap
from .null import PLAN_WALL_PX, NullNetwork

__all__ = ["NullNetwork", "NullCorrector", "ThesisCorrector", "DrawnCorrector", "PLAN_WALL_PX",
           "INPUT_EVIDENCE_WEIGHT"]

#: Weight of the input's own wall pixels beside the corrector's walls in the plan drawer's
#: evidence (:class:`DrawnCorrector`): enough that a wall run the input shows is drawn
#: whole where the corrector dropped a piece of it, too little to move the corrector's
#: lines. On 100 ds0 pairs (``python -m benchmarks.bench_drawing --data ds0 --model
#: none``), input runs >= 1 m broken: 201 of 2,234 without the input's pixels, 52 with
#: them at 0.1 (54 at 0.02); median Error on 40 val maps 1.012 / 1.158 / 1.151 px (input
#: 1.259), wall recall 0.65 / 0.69 / 0.69 (2026-11-27).
INPUT_EVIDENCE_WEIGHT = 0.1

class NullCorrector:
    """``none``: the post-processing with :class:`NullNetwork` inside (module docstring).

    Only the anchored, straightened pipeline has a meaning without a network:
    ``anchor=False`` or ``straighten=False`` (which draw the network's walls only) raise
    :class:`~map2map.core.errors.InputError` (in
    :func:`~map2map.learn.ba.autocorrect.autocorrect_many`); ``device`` is ignored.
    """

    name = "none"
    source = "none"

    def correct_many(self, maps: list[OccupancyMap], **options) -> list[OccupancyMap]:
        from .autocorrect import autocorrect_many

        options.pop("device", None)
        return [r.map for r in autocorrect_many(maps, NullNetwork(), **options)]


class ThesisCorrector:
    """The thesis's Model_BA: Model_32 (eqs. 3.1-3.7) and its post-processing.

    Parameters
    ----------
    weights : "pretrained", run folder or weights file
        Loaded at once (:func:`~map2map.learn.ba.model.load_model`: one clear error for a
        missing or wrong file).
    device : str
        Torch device.
    name : str, optional
        What tables and messages call it (default ``"thesis"`` for the shipped weights,
        else the path as given).
    """

    def __init__(self, weights: str | os.PathLike = "pretrained", device: str = "cpu",
                 name: str | None = None):
        from .model import load_model

        self.net = load_model(weights, device)
        self.device = device
        self.name = name or ("thesis" if str(weights) == "pretrained" else os.fspath(weights))
        self.source = self.net.source

    def correct_many(self, maps: list[OccupancyMap], **options) -> list[OccupancyMap]:
        from .autocorrect import autocorrect_many

        options.pop("device", None)
        return [r.map for r in autocorrect_many(maps, self.net, device=self.device,
                                                **options)]


class DrawnCorrector:
    """Another corrector's output drawn like a plan (issue #32 item 3).

    The walls ``base`` outputs are the evidence of the plan drawer
    (:func:`map2map.maps.vectorize.draw_plan_map`): straight walls at the map's dominant
    angle, the pieces of one wall line joined unless free space passes through the gap
    into rooms on both sides (a door), corners and T-junctions closed, every wall at one
    thickness, specks and ray fans gone. Doors, free and unknown space are the *input's*
    (an opening only where the input shows free space through the wall: ``base`` may
    have dropped a wall piece as clutter, which is no reason to open the wall). The
    output's ``meta["autocorrect"]["segments_px"]`` are the drawer's segments, so the map
    and its DXF (``map2map autocorrect --dxf``) show the same walls. A map ``base``
    returned as it is (``large="refuse"``, or nothing known) stays as it is. From 16
    maps on, the drawer runs in worker processes, one per core
    (:func:`map2map.maps.vectorize.draw_plan_maps`; the option ``workers`` sets how
    many, 1: none); with ``base`` a :class:`NullCorrector`, whose cleaning is per map
    (nothing in it is batched), each worker cleans and draws its maps, so that every
    core works throughout (:func:`map2map.core.parallel.process_map`). The outputs do
    not depend on either.

    Parameters
    ----------
    base : Corrector
        What finds the walls (``none``: the input's own, cleaned; ``thesis``: the input's
        and the network's).
    wall_thickness : float, optional
        Thickness of every wall in metres, at least one pixel (default: the plans'
        convention, :func:`map2map.maps.vectorize.default_wall_thickness`).
    input_weight : float
        Weight of the input's own wall pixels in the evidence, beside ``base``'s walls
        (weight 1): a wall the input shows whole is drawn whole
        (:data:`INPUT_EVIDENCE_WEIGHT`; 0: ``base``'s walls alone).
    options : DrawOptions, optional
        The drawer's tolerances (default: its defaults).

    Examples
    --------
    >>> import numpy as np
    >>> data = np.full((60, 80), 127, np.uint8); data[10:50, 10:70] = 255
    >>> data[10:12, 10:70] = 0; data[48:50, 10:70] = 0; data[10:50, 10:12] = 0
    >>> data[10:50, 68:70] = 0; data[10:12, 30:34] = 127       # a hole, not a door
    >>> out = DrawnCorrector(NullCorrector()).correct_many([OccupancyMap(data, 0.05)])[0]
    >>> bool((out.data[10:12, 30:34] == 0).all()), len(out.meta["autocorrect"]["segments_px"])
    (True, 4)
    """

    def __init__(self, base, wall_thickness: float | None = None,
                 input_weight: float = INPUT_EVIDENCE_WEIGHT, options=None):
        self.base, self.wall_thickness = base, wall_thickness
        self.input_weight, self.options = input_weight, options
        self.name, self.source = base.name, base.source

    def correct_many(self, maps: list[OccupancyMap], **options) -> list[OccupancyMap]:
        from ...core.parallel import process_map

        workers = options.get("workers")
        if isinstance(self.base, NullCorrector) and len(maps) >= _MIN_MAPS and (
                workers is None or int(workers) > 1):
            # cleaned and drawn in one worker per map: the cleaning's threads (1.6x on 2
            # cores) and then the drawer's processes left a core idle in between
            return process_map(_clean_and_draw, [(self, m, options) for m in maps],
                               workers=workers, min_items=_MIN_MAPS)
        return self._draw(maps, self.base.correct_many(maps, **options), workers)

    def _draw(self, maps: list[OccupancyMap], bases: list[OccupancyMap],
              workers: int | None) -> list[OccupancyMap]:
        """``bases`` (``base``'s outputs for ``maps``) drawn like a plan."""
        from ...maps.vectorize import draw_plan_maps, wall_points

        todo = [i for i, m in enumerate(bases)       # "refused": returned as it is
                if "refused" not in m.meta.get("autocorrect", {})]
        ev, ws, ts = [], [], []
        for i in todo:
            m, src = bases[i], maps[i]
            ts.append(None if self.wall_thickness is None
                      else max(1.0, self.wall_thickness / m.resolution))
            if self.input_weight > 0:
                p0, p1 = wall_points(m.occupied), wall_points(src.occupied)
                ev.append(np.concatenate([p0, p1]))
                ws.append(np.concatenate([np.ones(len(p0)),
                                          np.full(len(p1), self.input_weight)]))
            else:
                ev.append(m.occupied)
                ws.append(None)
        drawn_all = draw_plan_maps([maps[i] for i in todo], ev, ts, weights=ws,
                                   options=self.options, workers=workers,
                                   min_maps=_MIN_MAPS)
        out = list(bases)
        for i, (drawn, _) in zip(todo, drawn_all, strict=True):
            info = drawn.meta.pop("plan_drawer")
            ac = dict(bases[i].meta.get("autocorrect", {}))
            walls = ("segments_px", "arcs_px", "arc_of")
            ac.update({k: info[k] for k in walls if k in info},
                      drawn={k: v for k, v in info.items() if k not in walls})
            drawn.meta["autocorrect"] = ac
            out[i] = drawn
        return out


#: From this many maps on, :class:`DrawnCorrector` works in worker processes.
_MIN_MAPS = 16


def _clean_and_draw(job: tuple) -> OccupancyMap:
    """One map cleaned by a :class:`DrawnCorrector`'s :class:`NullCorrector` and drawn,
    in one process (a worker's job: ``(corrector, map, correct_many's options)``)."""
    corrector, m, options = job
    options = {**options, "workers": 1}
    return corrector._draw([m], corrector.base.correct_many([m], **options), 1)[0]
