"""Decomposition of a map into faces (rooms) and their oriented minimum bounding boxes.

Section 3.2.1 / Fig. 2 of the appendix paper, after Shahbandi & Magnusson: the wall
lines found by radiography (:mod:`.radiography`), with their doorway gaps bridged,
cut the free space into faces; each face large enough to be a room is kept and
represented by its oriented minimum bounding box (OMBB, ``cv2.minAreaRect``), which
removes the distortion of its shape.

Examples
--------
>>> import numpy as np
>>> img = np.full((40, 70), 127, np.uint8)
>>> img[5:35, 5:65] = 0; img[6:34, 6:64] = 255   # a 58 x 28 room ...
>>> img[6:34, 35] = 0; img[18:22, 35] = 255       # ... split by a wall with a door
>>> faces = decompose(img, theta=0.0, min_area=20, gap=6)
>>> sorted(round(f.area) for f in faces)
[784, 812]
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ..core.grid import FREE, OCCUPIED
from .radiography import wall_lines

__all__ = ["Face", "decompose", "face_image"]


@dataclass(frozen=True)
class Face:
    """One face (room) of a decomposition.

    ``centre`` (x, y), ``size`` (w, h) and ``angle`` (degrees) are the OMBB as
    ``cv2.minAreaRect`` returns it; ``area`` is the number of free cells.
    """

    label: int
    area: float
    centre: tuple[float, float]
    size: tuple[float, float]
    angle: float

    def extents(self, theta: float) -> tuple[float, float]:
        """OMBB side lengths along ``theta`` and ``theta + pi/2`` (the map's wall axes)."""
        a = np.radians(self.angle)
        along = abs(np.cos(a - theta))  # |cos| of the angle between side w and axis theta
        w, h = self.size
        return (w, h) if along >= np.sqrt(0.5) else (h, w)


def decompose(
    data: np.ndarray,
    theta: float,
    *,
    min_area: float = 30.0,
    min_length: float = 8.0,
    gap: int = 6,
    return_labels: bool = False,
):
    """Faces of ``data`` cut by its wall lines along ``theta`` and ``theta + pi/2``.

    Parameters
    ----------
    data : (H, W) uint8 occupancy map (usually at reduced resolution).
    theta : dominant orientation (radians).
    min_area : smallest face kept, in cells.
    min_length, gap : wall-line parameters (see :func:`.radiography.wall_lines`);
        ``gap`` is the widest doorway closed, in pixels.
    return_labels : also return the (H, W) int32 label image (0 = no face).
    """
    segs = wall_lines(data, theta, min_length=min_length, gap=gap)
    barrier = (data == OCCUPIED).astype(np.uint8)
    for x0, y0, x1, y1 in segs:
        cv2.line(
            barrier,
            (int(round(x0 - 0.5)), int(round(y0 - 0.5))),
            (int(round(x1 - 0.5)), int(round(y1 - 0.5))),
            1,
            thickness=1,
        )
    space = ((data == FREE) & (barrier == 0)).astype(np.uint8)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(space, connectivity=4)
    faces: list[Face] = []
    keep = np.zeros(n, np.int32)
    for lab in range(1, n):
        area = float(stats[lab, cv2.CC_STAT_AREA])
        if area < min_area:
            continue
        x, y, w, h = stats[lab, :4]
        sub = labels[y : y + h, x : x + w] == lab
        rr, cc = np.nonzero(sub)
        # pixel corners of the face, so a one-cell-wide face has a non-zero box
        pts = np.concatenate(
            [np.column_stack([cc + x + dx, rr + y + dy]) for dx in (0, 1) for dy in (0, 1)]
        ).astype(np.float32)
        (cx, cy), (bw, bh), ang = cv2.minAreaRect(pts)
        faces.append(Face(len(faces) + 1, area, (float(cx), float(cy)), (bw, bh), float(ang)))
        keep[lab] = len(faces)
    if return_labels:
        return faces, keep[labels]
    return faces


def face_image(labels: np.ndarray) -> np.ndarray:
    """(H, W, 3) float colour image of a face label image (for figures)."""
    rng = np.random.default_rng(0)
    colours = rng.uniform(0.35, 0.95, (int(labels.max()) + 1, 3))
    colours[0] = 1.0
    return colours[labels]
