"""Moving a SLAM map's walls by a displacement field, and the registration loss that
says where they belong (issue #32: the building blocks of a Model_BA that moves walls).

A wall *face* is an occupied pixel whose 4-neighbour in one direction (+x, -x, +y, -y;
x = column, y = row) is free (:func:`face_sets`). A SLAM face belongs on a plan face looking
the same way -- the side-aware matching of the appendix's eq. 7 on the four grid
directions -- so the registration loss samples, where a field moves each SLAM face, the
distance to the nearest plan face looking its way (:func:`face_distances`), robustly
(Charbonnier), over the faces within 4 px of one (the others are clutter, not misplaced
walls), plus a smoothness term on the field's control points (:func:`fit_field`).
:func:`warp` applies a field to a map. ``python -m map2map.experiments.table53.field_ceiling``
fits a field to each map's own plan: the most a field of this kind can do.

Examples
--------
>>> import numpy as np
>>> m = np.full((6, 6), 127, np.uint8); m[1:5, 2:5] = 255; m[1:5, 1] = 0
>>> f = face_sets(m); int(f[0].sum()), int(f[2].sum())   # the wall at column 1 looks +x
(4, 0)
>>> u = np.zeros((2, 6, 6), np.float32); u[0] = 1.0      # one pixel to the right
>>> bool((warp(m, u)[1:5, 2] == 0).all())
True
"""

from __future__ import annotations

import cv2
import numpy as np

from ...core.grid import UNKNOWN
from ...evaluate.features import side_masks
from ...evaluate.fitness import distance_map

__all__ = ["DIRECTIONS", "face_sets", "face_distances", "fit_field", "warp"]

#: Directions a face looks, in channel order (x = column, y = row): the sides ``k pi/2``
#: of :func:`map2map.evaluate.features.side_masks` on the grid's axes.
DIRECTIONS = ("+x", "+y", "-x", "-y")


def face_sets(m: np.ndarray) -> np.ndarray:
    """(4, H, W) bool: occupied pixels whose 4-neighbour in each of :data:`DIRECTIONS` is
    free -- the evaluation's wall surfaces (:func:`~map2map.evaluate.features.side_masks`)
    at angle 0.

    >>> m = np.full((6, 6), 127, np.uint8); m[1:5, 2:5] = 255; m[1:5, 1] = 0
    >>> f = face_sets(m); int(f[0].sum()), int(f[2].sum())
    (4, 0)
    """
    return np.stack(side_masks(m, 0.0))


def face_distances(plan: np.ndarray, clip: float = 8.0) -> np.ndarray:
    """(4, H, W) float32: distance to the nearest plan face looking each way, clipped."""
    return np.stack([np.minimum(distance_map(f), clip) for f in face_sets(plan)]
                    ).astype(np.float32)


def fit_field(slam: np.ndarray, plan_b: np.ndarray, grid: int, smooth: float,
              steps: int = 150) -> np.ndarray:
    """(2, H, W) field (x, y px) fitted to the plan (module docstring, 1)."""
    import torch
    import torch.nn.functional as F

    torch.manual_seed(0)
    H, W = slam.shape
    d = torch.from_numpy(face_distances(plan_b))[None]
    fb = torch.from_numpy(face_sets(slam))[None]
    d0 = torch.where(fb, d, torch.full_like(d, 1e3)).amin(1)
    w = ((fb.any(1)) & (d0 <= 4)).float()
    ys, xs = torch.meshgrid(torch.arange(H, dtype=torch.float32),
                            torch.arange(W, dtype=torch.float32), indexing="ij")
    f = torch.zeros(1, 2, grid, grid, requires_grad=True)
    opt = torch.optim.Adam([f], 0.05)
    big = torch.full_like(d, 1e3)

    def dense(f):
        return F.interpolate(f, size=(H, W), mode="bicubic", align_corners=False)

    for _ in range(steps):
        u = dense(f)
        g = torch.stack([(xs + u[:, 0] + 0.5) / W * 2 - 1, (ys + u[:, 1] + 0.5) / H * 2 - 1], -1)
        dm = F.grid_sample(d, g, mode="bilinear", padding_mode="border", align_corners=False)
        dd = torch.where(fb, dm, big).amin(1).clamp(max=6)
        reg = ((torch.sqrt(dd ** 2 + 0.04) - 0.2) * w).sum() / w.sum().clamp(min=1)
        sm = (((f[:, :, 1:] - f[:, :, :-1]) ** 2).mean()
              + ((f[:, :, :, 1:] - f[:, :, :, :-1]) ** 2).mean())
        opt.zero_grad()
        (reg + smooth * sm).backward()
        opt.step()
    return dense(f.detach())[0].numpy()


def warp(m: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The map with every pixel moved by ``u`` (backward nearest-neighbour resampling)."""
    H, W = m.shape
    ys, xs = np.mgrid[0:H, 0:W].astype(np.float32)
    return cv2.remap(m, xs - u[0], ys - u[1], cv2.INTER_NEAREST,
                     borderMode=cv2.BORDER_CONSTANT, borderValue=UNKNOWN)
