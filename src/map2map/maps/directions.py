"""Wall directions of a map: where a SLAM map's rooms run at different angles (issue #32).

A particle filter's heading error turns everything the robot maps while it lasts: on a
simulated rbpf map the walls of a room or of a wing can run several degrees off the rest
(`map2map.experiments.table53.unturn`: straight pieces lie a median 0.86 degrees off
the map's dominant direction, a tenth of them over 2.6). The plan drawer
(:mod:`map2map.maps.vectorize`) finds the walls of two orthogonal families at one
dominant angle and lets a long wall lean by up to 6 degrees; a wing turned by more is
drawn at the map's angle, across its own walls, which breaks them. This module tells
such wings apart:

1. **Local orientation** (:func:`orientation`): the structure tensor of the wall evidence
   (Sobel gradients, products averaged over a 9 x 9 box), its orientation folded modulo
   90 degrees (a wall and the walls square to it count alike) and its coherence.
2. **Deviation field**: each wall pixel's orientation less the dominant angle, folded
   into [-45, 45), averaged over its neighbourhood (a Gaussian of ``sigma`` metres,
   weighted by coherence) so that a room's walls vote together and a ragged wall's
   noise averages out. The average goes around the circle (of four times the
   deviation): a wing at 45 degrees, whose walls fold to +45 and -45 alike, averages to
   45, not 0.
3. **Families** (:func:`angle_families`): beside the dominant angle, a further angle
   where at least ``min_share`` of the evidence (and ``min_len`` metres of wall)
   deviates by more than ``min_dev`` degrees, around one mode; its angle is refined
   like the dominant one (the sharpest projections, 0.1 degree steps). Each wall point
   joins the family whose deviation is nearest its neighbourhood's. Other wall points
   (``votes``: the drawer's input wall pixels) may add a family at least 20 degrees
   off every other, a building's own second direction.

Examples
--------
>>> import cv2
>>> img = np.zeros((200, 200), np.uint8)
>>> img[20:22, 10:90] = 1; img[80:82, 10:90] = 1; img[20:82, 10:12] = 1   # a room at 0
>>> img[20:82, 88:90] = 1
>>> box = cv2.boxPoints(((145.0, 130.0), (90.0, 70.0), 10.0))           # one turned by 10
>>> _ = cv2.polylines(img, [np.round(box).astype(np.int32)], True, 1, 2)
>>> r, c = np.nonzero(img)
>>> pts = np.stack([c + 0.5, r + 0.5], 1)
>>> angles, label = angle_families(pts, np.ones(len(pts)), img.shape, 0.0, 0.05)
>>> [round(a) for a in angles]
[0, 10]
>>> bool((label[c < 90] == 0).all()), bool((label[c > 110] == 1).all())
(True, True)
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from ..core.runs import pixels

__all__ = ["splat", "orientation", "sharp_angle", "angle_families"]


def splat(pts: np.ndarray, w: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Summed weights of points ``(x, y)`` per pixel (nearest pixel; outside: dropped).

    >>> splat(np.array([[0.5, 0.5], [0.7, 0.2], [2.5, 1.5]]), np.ones(3), (2, 3)).tolist()
    [[2.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    """
    H, W = shape
    c = np.floor(pts[:, 0]).astype(np.int64)
    r = np.floor(pts[:, 1]).astype(np.int64)
    ok = (r >= 0) & (r < H) & (c >= 0) & (c < W)
    return np.bincount(r[ok] * W + c[ok], w[ok], H * W).reshape(H, W)


def orientation(img: np.ndarray, box: int = 9, at: tuple[np.ndarray, np.ndarray] | None = None,
                coherent: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Per pixel, the structure tensor's orientation (degrees, folded into [0, 90)) and
    its coherence (``|(Jxx - Jyy, 2 Jxy)|``), gradient products averaged over a ``box``
    square; only at the pixels ``at`` (rows, columns) when given; with ``coherent``,
    only at the pixels whose coherence exceeds ``coherent`` times the largest, in row-major
    order (1-D; the arctangent, most of the cost, is taken there only).

    >>> img = np.zeros((30, 30), np.float32); img[14:16, 3:27] = 1
    >>> ang, coh = orientation(img)
    >>> float(ang[15, 15]), bool(coh[15, 15] > 0)
    (0.0, True)
    >>> orientation(img, at=(np.array([15]), np.array([15])))[0].tolist()
    [0.0]
    >>> a, c = orientation(img, coherent=0.5)          # the strongly oriented pixels only
    >>> a.shape == c.shape and len(a) < img.size and bool((c > 0.5 * coh.max()).all())
    True
    """
    img = np.asarray(img, np.float32)
    gx = cv2.Sobel(img, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(img, cv2.CV_32F, 0, 1, ksize=3)
    jxx = cv2.blur(gx * gx, (box, box))
    jyy = cv2.blur(gy * gy, (box, box))
    jxy = cv2.blur(gx * gy, (box, box))
    if at is not None:
        jxx, jyy, jxy = jxx[at], jyy[at], jxy[at]
    coh = np.hypot(jxx - jyy, 2 * jxy)
    if coherent is not None:
        sel = coh > coherent * max(float(coh.max()), 1e-12)
        jxx, jyy, jxy, coh = jxx[sel], jyy[sel], jxy[sel], coh[sel]
    ang = np.degrees(0.5 * np.arctan2(2 * jxy, jxx - jyy)) % 90.0
    return ang, coh


#: Gaussian kernel (quarter-pixel bins, sigma 0.7 px) that :func:`_sharpness` smooths with.
_KDE = np.exp(-0.5 * (np.arange(-8, 9) / 2.8) ** 2)


def _sharpness(pts: np.ndarray, w: np.ndarray, angles) -> np.ndarray:
    """Per angle of ``angles``, the sum of squares of the smoothed density of the points'
    projections onto the axes turned by it (quarter-pixel bins, linear binning, then a
    Gaussian of 0.7 px: the score of a raster's pixel centres does not jump where they
    fall on the bins). All angles' bins are counted in one ``bincount`` (each angle's
    bins at its own offset), which sums every bin in the same order as one call per
    angle would."""
    cs = np.array([math.cos(math.radians(a)) for a in angles])[:, None]
    sn = np.array([math.sin(math.radians(a)) for a in angles])[:, None]
    x, y = pts[None, :, 0], pts[None, :, 1]
    s = np.zeros(len(cs))
    for q in (x * cs + y * sn, -x * sn + y * cs):
        z = (q - q.min(axis=1, keepdims=True)) * 4.0
        i = np.floor(z).astype(np.int64)
        f = z - i
        n = i.max(axis=1) + 2                        # bins per angle
        off = (np.cumsum(n) - n)[:, None]
        h = (np.bincount((i + off).ravel(), (w * (1 - f)).ravel(), int(n.sum()))
             + np.bincount((i + 1 + off).ravel(), (w * f).ravel(), int(n.sum())))
        for k, (o, nk) in enumerate(zip(off[:, 0].tolist(), n.tolist(), strict=True)):
            s[k] += float(np.square(np.convolve(h[o:o + nk], _KDE)).sum())
    return s


def sharp_angle(pts: np.ndarray, w: np.ndarray, start: float, span: float = 3.0) -> float:
    """The angle near ``start`` whose projections of the points onto both axes are
    sharpest (:func:`_sharpness`): ``start +- span`` in 0.5 degree steps (moved on by
    ``span`` while the sharpest lies at an edge, up to 5 times), then +-0.4 in steps of
    0.1 (a few angles, not pixels; at most 2,000 points, every k-th).

    >>> pts = np.stack([np.arange(100.0), 50 + np.arange(100.0) * math.tan(math.radians(2))], 1)
    >>> round(sharp_angle(pts, np.ones(100), 0.0), 1)
    2.0
    >>> round(sharp_angle(pts, np.ones(100), -4.0), 1)        # a start 6 degrees off
    2.0
    """
    if len(pts) > 2000:                                     # every k-th point: enough
        k = int(math.ceil(len(pts) / 2000))
        pts, w = pts[::k], w[::k]

    def sharpest(cand: np.ndarray) -> tuple[float, int]:
        i = int(np.argmax(_sharpness(pts, w, cand)))
        return float(cand[i]), i

    cand = start + np.arange(-span, span + 0.25, 0.5)
    best, i = sharpest(cand)
    for _ in range(5):
        # the sharpest at an edge of the window: ``start`` was off by more than ``span``
        # (a ragged wall's structure tensor), so the window walks on, at most 5 times
        if 0 < i < len(cand) - 1:
            break
        cand = best + np.arange(-span, span + 0.25, 0.5)
        best, i = sharpest(cand)
    return sharpest(best + np.arange(-0.4, 0.45, 0.1))[0]


def _smooth(sigma: float, *arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    """The ``arrays`` (2-4, float32) smoothed by a Gaussian of ``sigma`` pixels; a wide one on
    a grid pooled by about ``sigma / 4`` (area averages) and brought back bilinearly, in
    a twentieth of the time: a smooth kernel about as wide (on the maps' walls it differs
    from the exact Gaussian by a median 7 % of the peak, at most 17 %), enough for
    averaging deviations, whose ratio is what counts."""
    ab = cv2.merge(list(arrays))
    H, W = arrays[0].shape
    f = int(sigma // 4)
    if f < 2:
        out = cv2.GaussianBlur(ab, (0, 0), sigma)
    else:
        small = cv2.resize(ab, (max(1, -(-W // f)), max(1, -(-H // f))),
                           interpolation=cv2.INTER_AREA)
        out = cv2.resize(cv2.GaussianBlur(small, (0, 0), sigma / f), (W, H),
                         interpolation=cv2.INTER_LINEAR)
    return tuple(out[..., k] for k in range(len(arrays)))


def _wrap(x):
    """Degrees folded into [-45, 45): a direction and the one square to it alike."""
    return (x + 45.0) % 90.0 - 45.0


def _apart(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """How far deviations lie apart, modulo 90 degrees."""
    return np.abs(_wrap(a - b))


def angle_families(points: np.ndarray, weights: np.ndarray, shape: tuple[int, int],
                   angle: float, resolution: float, *, min_dev: float = 5.0,
                   min_share: float = 0.15, min_len: float = 4.0, sigma: float = 1.0,
                   max_families: int = 3, votes: tuple[np.ndarray, np.ndarray] | None = None,
                   votes_min_dev: float = 20.0) -> tuple[list[float], np.ndarray]:
    """Direction families of wall points (module doc): their angles (degrees, image
    frame, the dominant ``angle`` first) and each point's family.

    Parameters
    ----------
    points : (N, 2) float
        Wall points ``(x, y)``, continuous pixel coordinates.
    weights : (N,) float
    shape : (H, W)
        The map's shape.
    angle : float
        The dominant direction (:func:`map2map.maps.vectorize.dominant_angle`).
    resolution : float
        Metres per pixel.
    min_dev : float
        Degrees a further family lies off every other at least.
    min_share, min_len : float
        Share of the points' weight, and metres of wall (points per pixel of length:
        about two, the two faces of a wall or one thick line), a further family needs.
    sigma : float
        Metres: the neighbourhood over which the deviation is averaged.
    max_families : int
    votes : ((M, 2), (M,)) float, optional
        Other wall points and weights that may add families the points miss, at least
        ``votes_min_dev`` degrees off every family (a building's own second direction,
        not a wing SLAM turned): the drawer passes the input's own wall pixels, whose
        walls in every direction are there, where its evidence may hold a corrector's
        walls in the main directions only. When they add one, ``points`` are labelled
        by their field.
    votes_min_dev : float
        Degrees. Wings turned by drift lie 5-15 degrees off (the dev build); taken from
        the input's walls they would be drawn at their turn, which the cleaning rightly
        undoes (Table 5.3 on the dev build: 5 maps, all worse, 1.67 -> 3.34 px at most).

    Returns
    -------
    angles : list of float
    label : (N,) int
        Index into ``angles``.
    """
    pts = np.asarray(points, float).reshape(-1, 2)
    w = np.asarray(weights, float).reshape(-1)
    label = np.zeros(len(pts), np.int64)
    if len(pts) < 3 or max_families < 2:
        return [float(angle)], label
    s = max(1.0, sigma / float(resolution))
    field = _Field(pts, w, shape, angle, s)
    need = max(min_share * float(w.sum()), 2.0 * min_len / float(resolution) * float(w.max()))
    devs = field.families([0.0], pts, w, need, min_dev, max_families, angle)
    if votes is not None and len(devs) < max_families:
        vp = np.asarray(votes[0], float).reshape(-1, 2)
        vw = np.asarray(votes[1], float).reshape(-1)
        if len(vp) >= 3:
            vfield = _Field(vp, vw, shape, angle, s)
            vneed = max(min_share * float(vw.sum()),
                        2.0 * min_len / float(resolution) * float(vw.max()))
            more = vfield.families(devs, vp, vw, vneed, votes_min_dev, max_families, angle)
            if len(more) > len(devs):
                devs, field = more, vfield
    if len(devs) > 1:
        label = field.labels(pts, np.asarray(devs), min_dev)
    angles = [float(angle)] + [round(float(_wrap(angle + x)), 1) for x in devs[1:]]
    return angles, label


class _Field:
    """The deviation field of wall points (module doc, step 2) and the family search
    and labelling on it (step 3).

    The deviations are averaged around the circle (of ``4 dev``: walls at +44 and -44
    degrees average to 45, not 0), weighted by coherence: the smoothed images of
    ``c cos(4 dev)``, ``c sin(4 dev)`` and ``c``, built at the wall pixels only and
    smoothed once per neighbourhood size."""

    def __init__(self, pts: np.ndarray, w: np.ndarray, shape: tuple[int, int], angle: float,
                 s: float):
        img = splat(pts, w, shape).astype(np.float32)
        at = pixels(img > 0)                       # the wall pixels only: a few thousand
        ang, coh = orientation(img, at=at)
        t = np.radians(4.0 * _wrap(ang - angle))
        self.imgs = []
        for v in (coh * np.cos(t), coh * np.sin(t), coh):
            im = np.zeros(shape, np.float32)
            im[at] = v
            self.imgs.append(im)
        self.s, self.shape, self._smoothed = s, shape, {}

    def _at(self, pts: np.ndarray, s: float) -> tuple[np.ndarray, np.ndarray]:
        """The mean deviation (degrees) around each point, and where there is weight."""
        if s not in self._smoothed:
            self._smoothed[s] = _smooth(s, *self.imgs)
        cs, sn, den = self._smoothed[s]
        H, W = self.shape
        r = np.clip(np.floor(pts[:, 1]).astype(np.int64), 0, H - 1)
        q = np.clip(np.floor(pts[:, 0]).astype(np.int64), 0, W - 1)
        ok = den[r, q] > 1e-6 * max(float(den.max()), 1e-12)
        return np.where(ok, _wrap(np.degrees(np.arctan2(sn[r, q], cs[r, q])) / 4.0), 0.0), ok

    def families(self, devs: list[float], pts: np.ndarray, w: np.ndarray, need: float,
                 min_dev: float, max_families: int, angle: float) -> list[float]:
        """``devs`` and the further families the points' deviations show, each at least
        ``min_dev`` off every other, up to ``max_families``."""
        d, _ = self._at(pts, self.s)
        devs = list(devs)
        while len(devs) < max_families:
            far = np.min(_apart(d[:, None], np.asarray(devs)[None, :]), axis=1) >= min_dev
            if float(w[far].sum()) < need:
                break
            # the mode of the far points' deviations (0.5 degree bins, smoothed around
            # the circle: -45 and +45 degrees are one direction)
            b = np.clip(((d[far] + 45.0) * 2).astype(np.int64), 0, 179)
            h = np.bincount(b, w[far], 180)
            hist = np.convolve(np.concatenate([h[-2:], h, h[:2]]), [1.0, 2, 3, 2, 1],
                               "valid")
            mode = (int(np.argmax(hist)) + 0.5) / 2.0 - 45.0
            near = far & (_apart(d, mode) <= 2.0)
            if float(w[near].sum()) < need:
                break
            a = sharp_angle(pts[near], w[near], angle + mode, 2.0)
            dv = _wrap(a - angle)
            if min(float(_apart(dv, x)) for x in devs) < min_dev:
                break
            devs.append(dv)
        return devs

    def labels(self, pts: np.ndarray, dv: np.ndarray, min_dev: float) -> np.ndarray:
        """Each point's family: the nearest deviation of its neighbourhood's; near the
        border of two wings the wide average mixes them, so where the wall's own
        orientation (averaged over a fifth of the neighbourhood) is clearly nearer one
        family, it decides."""
        d, _ = self._at(pts, self.s)
        label = np.argmin(_apart(d[:, None], dv[None, :]), axis=1)
        d2, ok2 = self._at(pts, max(1.0, 0.2 * self.s))
        gap = np.sort(_apart(d2[:, None], dv[None, :]), axis=1)
        sure = ok2 & (gap[:, 1] - gap[:, 0] >= 0.5 * min_dev)
        return np.where(sure, np.argmin(_apart(d2[:, None], dv[None, :]), axis=1), label)
