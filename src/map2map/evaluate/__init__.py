"""Map evaluation: how far apart a SLAM map and its floor plan are, where, in centimetres.

The appendix paper of the thesis ("Automated Robotic Assessment of 2D As-built
Floor Plans", section 3.2, Fig. 1), one concept per module, in the order of the
data flow:

=====================  ===================================================================
:mod:`.orientation`    dominant wall orientations (gradient histogram, Radon), direction families
:mod:`.radiography`    wall lines by Radon-type projections along those orientations
:mod:`.decomposition`  faces (rooms) cut by the wall lines, oriented minimum bounding boxes
:mod:`.hypotheses`     similarity hypotheses from face pairs (+ dense FFT ones), rejection
:mod:`.fitness`        Gaussian distance map and the fitness of eq. 8
:mod:`.align`          global similarity, affine refinement, rigid variant (3.2.1)
:mod:`.anchors`        anchoring, eqs. 1-6, and automatic anchors (3.2.2)
:mod:`.nonrigid`       optimisation of eq. 7 (near-linear coherence), piecewise-affine warp
:mod:`.metric`         Algorithm 1 (local errors, both chains, the chain rule), IoU
:mod:`.icp`            vanilla ICP baseline
:mod:`.pipeline`       :func:`register` (align) and :func:`evaluate_maps` (evaluate)
:mod:`.figures`        overlay, error heat map, batch box plot
:mod:`.outputs`        the files of ``map2map align`` / ``map2map evaluate``
=====================  ===================================================================

Pixel coordinates are ``x`` = column, ``y`` = row, origin at the top-left corner,
continuous (the centre of pixel ``(r, c)`` is ``(c + 0.5, r + 0.5)``); every 3x3
matrix maps source (SLAM) pixels to target (plan) pixels.

Maps with known errors (:mod:`map2map.maps.synthetic`) and the reader of the
Halmstad annotated maps (:mod:`map2map.maps.halmstad`) live in ``maps``: any layer
may build test maps or read the data.

Examples
--------
>>> from map2map.core.grid import OccupancyMap
>>> from map2map.evaluate import evaluate_maps
>>> from map2map.maps.synthetic import draw_walls, office_walls
>>> plan = OccupancyMap(draw_walls((240, 300), office_walls(300, 240)), 0.05)
>>> moved = office_walls(300, 240, corridor_shift=(4, 0))
>>> built = OccupancyMap(draw_walls((240, 300), moved), 0.05)
>>> ev = evaluate_maps(built, plan, resolution=0.05)
>>> round(ev.report["chosen_errors"]["max_m"], 1)        # a corridor wall built 20 cm off
0.2
"""

from .align import Alignment, AlignParams, align_maps
from .pipeline import EvaluateParams, Evaluation, Registration, evaluate_maps, register

__all__ = [
    "AlignParams",
    "Alignment",
    "align_maps",
    "EvaluateParams",
    "Evaluation",
    "Registration",
    "evaluate_maps",
    "register",
]
