"""Counting occupancy grids, GMapping's scan score and likelihood fields (numba kernels).

Occupancy follows GMapping's ``PointAccumulator`` (Grisetti et al. 2007, and the
``gmapping`` ROS package): every cell counts how often a beam *visited* it and how
often a beam *ended* in it (a hit). Its occupancy is ``hits / visits``; a cell is
occupied above ``occ_thresh`` (0.25, slam_gmapping's default), free below it, and
unknown while never visited. Each cell also accumulates the world position of the
hits that fell in it, so the scan matcher compares an endpoint with the *mean hit*
of a cell (sub-cell accuracy), as GMapping does.

Grid layout: arrays are indexed ``[iy, ix]`` where ``ix = floor((x - x0) / delta)``
and ``iy = floor((y - y0) / delta)``; ``(x0, y0)`` is the world corner of cell
``(0, 0)``. :meth:`CountGrid.to_occupancy_map` flips the rows into the package's
image order (row 0 at the top, see :mod:`map2map.core.grid`).

Two scan scores are provided:

* :func:`gmapping_score` / :func:`hill_climb` -- GMapping's ``ScanMatcher::score``
  and ``ScanMatcher::optimize``: each endpoint looks in a ``(2k+1)^2`` kernel for
  the nearest occupied cell whose predecessor along the beam is not occupied.
* :func:`likelihood_field` -- a distance-transform likelihood field
  (``exp(-d^2 / 2 sigma^2)``, Thrun et al. "Probabilistic Robotics" 6.4) used by
  the correlative scan matcher of :mod:`map2map.slam.graph`.

Examples
--------
>>> import numpy as np
>>> g = CountGrid.around(0.0, 0.0, half_size=2.0, delta=0.05)
>>> angles = np.deg2rad(np.arange(0, 360, 1.0))
>>> ranges = np.full(360, 1.0)
>>> g.register_scan((0.0, 0.0, 0.0), ranges, angles, usable_range=3.0)
>>> m = g.to_occupancy_map()
>>> int((m.data == 0).sum()) > 100        # a ring of occupied cells
True
"""

from __future__ import annotations

import math

import cv2
import numba as nb
import numpy as np

from ..core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap

__all__ = [
    "CountGrid",
    "register_scan",
    "gmapping_score",
    "hill_climb",
    "sample_likelihood",
    "likelihood_field",
    "occupancy_from_counts",
]

#: GMapping's ``ScanMatcher::m_fullnessThreshold``: a cell counts as a hit above it.
FULLNESS_THRESHOLD = 0.1
#: GMapping's ``nullLikelihood``: log-likelihood of a beam whose endpoint matched nothing.
NULL_LIKELIHOOD = -0.5
#: fastmath flags for the scoring kernel: everything but "no NaNs" (NaN marks free cells).
_FAST = {"nsz", "arcp", "contract", "afn", "reassoc"}


# ----------------------------------------------------------------------------- kernels
@nb.njit(cache=True)
def _bresenham_update(hits, visits, sx, sy, mean, x0, y0, x1, y1, hit, hx, hy, stop_at_wall):
    """Walk the Bresenham line (x0,y0)->(x1,y1); visit every cell but the last.

    The last cell gets a hit (with the world endpoint ``hx, hy``) when ``hit``.
    Cells outside the arrays are ignored. With ``stop_at_wall`` the walk ends at
    the first occupied cell (a beam without a return cannot have passed a wall).
    """
    ny, nx = visits.shape
    dx = abs(x1 - x0)
    dy = -abs(y1 - y0)
    stx = 1 if x0 < x1 else -1
    sty = 1 if y0 < y1 else -1
    err = dx + dy
    x, y = x0, y0
    while True:
        if x == x1 and y == y1:
            break
        if 0 <= x < nx and 0 <= y < ny:
            if stop_at_wall and mean[y, x, 0] == mean[y, x, 0]:
                return
            visits[y, x] += 1
            if hits[y, x] <= FULLNESS_THRESHOLD * visits[y, x]:
                mean[y, x, 0] = np.nan
        e2 = 2 * err
        if e2 >= dy:
            err += dy
            x += stx
        if e2 <= dx:
            err += dx
            y += sty
    if hit and 0 <= x1 < nx and 0 <= y1 < ny:
        visits[y1, x1] += 1
        hits[y1, x1] += 1
        sx[y1, x1] += hx
        sy[y1, x1] += hy
        h = hits[y1, x1]
        if h > FULLNESS_THRESHOLD * visits[y1, x1]:
            mean[y1, x1, 0] = sx[y1, x1] / h
            mean[y1, x1, 1] = sy[y1, x1] / h
        else:
            mean[y1, x1, 0] = np.nan


@nb.njit(cache=True)
def register_scan(
    hits,
    visits,
    sx,
    sy,
    mean,
    gx0,
    gy0,
    delta,
    lx,
    ly,
    lt,
    ranges,
    angles,
    usable_range,
    max_range,
    no_return_free,
):
    """Integrate one scan taken from laser pose ``(lx, ly, lt)`` (GMapping ``registerScan``).

    NaN or non-positive readings are skipped. Beams longer than ``max_range`` (no
    return) are skipped too, unless ``no_return_free``: then they clear free space up
    to ``usable_range`` -- GMapping's documented set-up "maxUrange < sensor range <=
    maxRange" for drivers that report a no-return at the sensor's maximum range.
    Beams longer than ``usable_range`` are cropped to it and mark only free space;
    the others mark free space up to the endpoint cell and a hit in it.

    Parameters
    ----------
    hits, visits : (H, W) int arrays
        Per-cell counts, updated in place.
    sx, sy : (H, W) float arrays
        Sums of the hit points' world x and y per cell, updated in place.
    mean : (H, W, 2) float array
        Mean hit point of each cell (NaN where the cell is not occupied enough),
        updated in place.
    gx0, gy0 : float
        World position of cell (0, 0).
    delta : float
        Cell size, metres.
    lx, ly, lt : float
        Laser pose.
    ranges, angles : float arrays
        The scan's readings (metres) and beam angles in the laser frame.
    usable_range : float
        GMapping's ``maxUrange``.
    max_range : float
        GMapping's ``maxRange``.
    no_return_free : bool
        Let no-return beams clear up to ``usable_range``.
    """
    cx0 = int(math.floor((lx - gx0) / delta))
    cy0 = int(math.floor((ly - gy0) / delta))
    for i in range(ranges.shape[0]):
        r = ranges[i]
        if not (r > 0.0):
            continue
        no_return = r > max_range
        if no_return:
            if not no_return_free:
                continue
            r = usable_range
        hit = True
        if r >= usable_range:
            r = usable_range
            hit = False
        a = lt + angles[i]
        hx = lx + r * math.cos(a)
        hy = ly + r * math.sin(a)
        cx1 = int(math.floor((hx - gx0) / delta))
        cy1 = int(math.floor((hy - gy0) / delta))
        _bresenham_update(hits, visits, sx, sy, mean, cx0, cy0, cx1, cy1, hit, hx, hy, no_return)


@nb.njit(cache=True)
def _beam_vectors(ranges, angles, off):
    """Endpoints ``(ex, ey)`` and unit directions ``(ux, uy)`` of the beams in the robot frame."""
    n = ranges.shape[0]
    out = np.empty((4, n))
    for i in range(n):
        a = off[2] + angles[i]
        c, s = math.cos(a), math.sin(a)
        out[0, i] = off[0] + ranges[i] * c
        out[1, i] = off[1] + ranges[i] * s
        out[2, i] = c
        out[3, i] = s
    return out


@nb.njit(cache=True, fastmath=_FAST, inline="always")
def _nearest_hit(mean, gx0, gy0, inv, free_back, hx, hy, ca, sa, kernel):
    """GMapping's kernel search for one endpoint ``(hx, hy)`` of a beam along ``(ca, sa)``.

    Among the ``(2 kernel + 1)^2`` cells around the endpoint, the occupied cell whose
    mean hit is nearest, provided the cell one step back along the beam
    (``delta * sqrt(2)``, GMapping's ``freeCellRatio``) is not occupied. Returns
    ``(d^2, mean_x, mean_y)``, ``d^2 = 1e30`` when nothing matched.
    """
    ny, nx = mean.shape[0], mean.shape[1]
    ix = int(math.floor((hx - gx0) * inv))
    iy = int(math.floor((hy - gy0) * inv))
    fx = int(math.floor((hx - free_back * ca - gx0) * inv)) - ix
    fy = int(math.floor((hy - free_back * sa - gy0) * inv)) - iy
    best = 1e30
    bx = 0.0
    by = 0.0
    for yy in range(-kernel, kernel + 1):
        cy = iy + yy
        cfy = cy + fy
        if cy < 0 or cy >= ny or cfy < 0 or cfy >= ny:
            continue
        for xx in range(-kernel, kernel + 1):
            cx = ix + xx
            cfx = cx + fx
            if cx < 0 or cx >= nx or cfx < 0 or cfx >= nx:
                continue
            # branch-free (the occupancy pattern is unpredictable, a mispredicted branch
            # costs more than the arithmetic): a cell that is not occupied has a NaN
            # mean, so its d2 is NaN and never below best; an occupied predecessor
            # (non-NaN) vetoes the cell
            mux = mean[cy, cx, 0]
            muy = mean[cy, cx, 1]
            pred = mean[cfy, cfx, 0]
            d2 = (hx - mux) * (hx - mux) + (hy - muy) * (hy - muy)
            take = (d2 < best) & (pred != pred)
            best = d2 if take else best
            bx = mux if take else bx
            by = muy if take else by
    return best, bx, by


@nb.njit(cache=True, fastmath=_FAST)
def _score_core(mean, gx0, gy0, delta, px, py, pt, beams, kernel, sigma, lsigma):
    """GMapping ``ScanMatcher::likelihoodAndScore`` at robot pose ``(px, py, pt)``.

    ``beams`` comes from :func:`_beam_vectors` (usable beams only). Each endpoint is
    matched by :func:`_nearest_hit`; the score adds ``exp(-d^2 / sigma)``, the
    log-likelihood adds ``-d^2 / lsigma``, or ``nullLikelihood / lsigma`` when
    nothing matched. Returns ``(score, loglik, n_matched)``.
    """
    ct, st = math.cos(pt), math.sin(pt)
    free_back = delta * math.sqrt(2.0)
    no_hit = NULL_LIKELIHOOD / lsigma
    inv = 1.0 / delta
    s = 0.0
    lik = 0.0
    n = 0
    for i in range(beams.shape[1]):
        ex, ey, ux, uy = beams[0, i], beams[1, i], beams[2, i], beams[3, i]
        hx = px + ct * ex - st * ey
        hy = py + st * ex + ct * ey
        ca = ct * ux - st * uy
        sa = st * ux + ct * uy
        best = _nearest_hit(mean, gx0, gy0, inv, free_back, hx, hy, ca, sa, kernel)[0]
        if best < 1e29:
            s += math.exp(-best / sigma)
            lik += -best / lsigma
            n += 1
        else:
            lik += no_hit
    return s, lik, n


@nb.njit(cache=True)
def gmapping_score(mean, gx0, gy0, delta, px, py, pt, off, ranges, angles, kernel, sigma, lsigma):
    """GMapping's scan score and log-likelihood at one pose; see :func:`_score_core`.

    Parameters
    ----------
    mean : (H, W, 2) float array
        Mean hit point of each cell (NaN: none), GMapping's likelihood reference.
    gx0, gy0 : float
        World position of the grid's cell (0, 0).
    delta : float
        Cell size, metres.
    px, py, pt : float
        Robot pose.
    off : (3,) float array
        Laser offset on the robot.
    ranges, angles : float arrays
        The scan's readings (metres) and beam angles in the laser frame.
    kernel : int
        Search half-width (cells) for the nearest hit.
    sigma, lsigma : float
        Score and likelihood standard deviations, metres.

    Returns
    -------
    score, loglik : float
    """
    beams = _beam_vectors(ranges, angles, off)
    return _score_core(
        mean,
        gx0,
        gy0,
        delta,
        px,
        py,
        pt,
        beams,
        kernel,
        sigma,
        lsigma,
    )


@nb.njit(cache=True)
def hill_climb(
    mean,
    gx0,
    gy0,
    delta,
    px,
    py,
    pt,
    off,
    ranges,
    angles,
    kernel,
    sigma,
    lstep,
    astep,
    iterations,
    prior,
):
    """GMapping's ``ScanMatcher::optimize``: greedy hill climbing with step halving.

    From ``(px, py, pt)`` try the six moves (x +- lstep, y +- lstep, theta +- astep),
    keep the best; when no move improves, halve the steps (a *refinement*); stop
    after ``iterations`` refinements without improvement. Returns ``(x, y, theta,
    score)`` -- the scan score of the best pose found. The reverse of the move just
    taken is not tried again (it returns to the pose that move improved on, a
    known lower score), which saves about one score in ten and changes nothing.

    ``prior`` is ``(mx, my, mt, wx, wy, wt)``: the climb maximises
    ``score - 0.5 (wx (x - mx)^2 + wy (y - my)^2 + wt (t - mt)^2)``, the motion-model
    factor of the improved proposal (Grisetti et al. 2007, eq. 9: the proposal is
    proportional to the scan likelihood *times* the odometry motion model). All
    weights zero is GMapping's code, which drops that factor; along a featureless
    corridor the score is flat and the match then slides freely.

    Parameters
    ----------
    mean : (H, W, 2) float array
        Mean hit point of each cell (NaN: none), GMapping's likelihood reference.
    gx0, gy0 : float
        World position of the grid's cell (0, 0).
    delta : float
        Cell size, metres.
    px, py, pt : float
        Start pose.
    off : (3,) float array
        Laser offset on the robot.
    ranges, angles : float arrays
        The scan's readings (metres) and beam angles in the laser frame.
    kernel : int
        Search half-width (cells) for the nearest hit.
    sigma : float
        Score standard deviation, metres.
    lstep, astep : float
        Initial linear (m) and angular (rad) steps.
    iterations : int
        Refinements allowed without improvement.
    prior : (6,) float array
        Motion-model prior (see above).

    Returns
    -------
    x, y, theta, score : float
    """
    beams = _beam_vectors(ranges, angles, off)
    cx, cy, ct = px, py, pt
    cur = _score_core(mean, gx0, gy0, delta, cx, cy, ct, beams, kernel, sigma, 1.0)[
        0
    ] - _prior_penalty(prior, cx, cy, ct)
    best_score = -1.0
    ld, ad = lstep, astep
    refinement = 0
    last = -1  # the move taken in the previous round (-1: none)
    while True:
        if best_score >= cur:
            refinement += 1
            ld *= 0.5
            ad *= 0.5
        best_score = cur
        bx, by, bt = cx, cy, ct
        # the reverse of the move just taken leads back to the pose it improved on
        skip = last ^ 1 if last >= 0 else -1
        last = -1
        for move in range(6):
            if move == skip:
                continue
            tx, ty, tt = cx, cy, ct
            if move == 0:
                tx += ld
            elif move == 1:
                tx -= ld
            elif move == 2:
                ty -= ld
            elif move == 3:
                ty += ld
            elif move == 4:
                tt += ad
            else:
                tt -= ad
            sc = _score_core(
                mean,
                gx0,
                gy0,
                delta,
                tx,
                ty,
                tt,
                beams,
                kernel,
                sigma,
                1.0,
            )[0] - _prior_penalty(prior, tx, ty, tt)
            if sc > cur:
                cur = sc
                bx, by, bt = tx, ty, tt
                last = move
        cx, cy, ct = bx, by, bt
        if not (cur > best_score or refinement < iterations):
            break
    return cx, cy, ct, best_score + _prior_penalty(prior, cx, cy, ct)


@nb.njit(cache=True, inline="always")
def _prior_penalty(prior, x, y, t):
    """``0.5 * sum w_i (p_i - m_i)^2`` of the motion prior ``(mx, my, mt, wx, wy, wt)``."""
    dt = t - prior[2]
    dt = (dt + math.pi) % (2.0 * math.pi) - math.pi
    return 0.5 * (
        prior[3] * (x - prior[0]) ** 2 + prior[4] * (y - prior[1]) ** 2 + prior[5] * dt * dt
    )


@nb.njit(cache=True)
def sample_likelihood(
    mean,
    gx0,
    gy0,
    delta,
    px,
    py,
    pt,
    off,
    ranges,
    angles,
    kernel,
    sigma,
    lsigma,
    lrange,
    lstep_,
    arange_,
    astep_,
):
    """Gaussian approximation of the proposal around a matched pose (Grisetti 2007, eq. 9-12).

    Evaluates the scan log-likelihood on the grid ``[-lrange, lrange]`` (step ``lstep_``)
    in x and y and ``[-arange_, arange_]`` (step ``astep_``) in theta around
    ``(px, py, pt)`` -- GMapping's ``llsamplerange``/``lasamplerange`` -- and returns
    ``(log_eta, mean (3,), cov (3, 3))`` where ``log_eta = log sum_j p(z | m, x_j)``
    is the importance-weight increment of the improved proposal. Each beam is
    matched (:func:`_nearest_hit`) once at the centre pose and keeps that match for
    all samples (they lie within ``lrange`` of it, well inside one cell).

    Parameters
    ----------
    mean : (H, W, 2) float array
        Mean hit point of each cell (NaN: none), GMapping's likelihood reference.
    gx0, gy0 : float
        World position of the grid's cell (0, 0).
    delta : float
        Cell size, metres.
    px, py, pt : float
        Matched pose.
    off : (3,) float array
        Laser offset on the robot.
    ranges, angles : float arrays
        The scan's readings (metres) and beam angles in the laser frame.
    kernel : int
        Search half-width (cells) for the nearest hit.
    sigma, lsigma : float
        Score and likelihood standard deviations, metres.
    lrange, lstep_, arange_, astep_ : float
        Sampling ranges and steps (metres, radians).

    Returns
    -------
    log_eta : float
    mean : (3,) float array
    cov : (3, 3) float array
    """
    beams = _beam_vectors(ranges, angles, off)
    nb_ = beams.shape[1]
    # nearest mean hits at the centre pose; the samples lie within a centimetre of it,
    # so each beam keeps its match and only the distance to it is re-evaluated
    ct, st = math.cos(pt), math.sin(pt)
    inv = 1.0 / delta
    free_back = delta * math.sqrt(2.0)
    mx = np.empty(nb_)
    my = np.empty(nb_)
    ok = np.zeros(nb_, np.bool_)
    for b in range(nb_):
        hx = px + ct * beams[0, b] - st * beams[1, b]
        hy = py + st * beams[0, b] + ct * beams[1, b]
        ca = ct * beams[2, b] - st * beams[3, b]
        sa = st * beams[2, b] + ct * beams[3, b]
        d2, mx[b], my[b] = _nearest_hit(mean, gx0, gy0, inv, free_back, hx, hy, ca, sa, kernel)
        ok[b] = d2 < 1e29
    no_hit = NULL_LIKELIHOOD / lsigma
    nl = int(round(lrange / lstep_)) if lstep_ > 0 else 0
    na = int(round(arange_ / astep_)) if astep_ > 0 else 0
    m = (2 * nl + 1) * (2 * nl + 1) * (2 * na + 1)
    ls = np.empty(m)
    ps = np.empty((m, 3))
    k = 0
    for i in range(-nl, nl + 1):
        for j in range(-nl, nl + 1):
            for q in range(-na, na + 1):
                x = px + i * lstep_
                y = py + j * lstep_
                t = pt + q * astep_
                c, s_ = math.cos(t), math.sin(t)
                lik = 0.0
                for b in range(nb_):
                    if ok[b]:
                        hx = x + c * beams[0, b] - s_ * beams[1, b] - mx[b]
                        hy = y + s_ * beams[0, b] + c * beams[1, b] - my[b]
                        lik -= (hx * hx + hy * hy) / lsigma
                    else:
                        lik += no_hit
                ls[k] = lik
                ps[k, 0] = x
                ps[k, 1] = y
                ps[k, 2] = t
                k += 1
    lmax = ls.max()
    w = np.exp(ls - lmax)
    tot = w.sum()
    w /= tot
    mu = np.zeros(3)
    for k in range(m):
        mu += w[k] * ps[k]
    cov = np.zeros((3, 3))
    for k in range(m):
        d = ps[k] - mu
        cov += w[k] * np.outer(d, d)
    return lmax + math.log(tot), mu, cov


@nb.njit(cache=True)
def occupancy_from_counts(hits, visits, occ_thresh):
    """Image-order (row 0 = top = largest y) uint8 map: 0 occupied, 255 free, 127 unknown.

    Parameters
    ----------
    hits, visits : (H, W) int arrays
        Per-cell counts (row 0 = smallest y).
    occ_thresh : float
        Hit ratio above which a visited cell is occupied.

    Returns
    -------
    (H, W) uint8 array

    Examples
    --------
    >>> hits = np.array([[0, 3, 0]]); visits = np.array([[0, 4, 5]])
    >>> occupancy_from_counts(hits, visits, 0.25).tolist()
    [[127, 0, 255]]
    """
    ny, nx = visits.shape
    out = np.empty((ny, nx), np.uint8)
    for iy in range(ny):
        r = ny - 1 - iy
        for ix in range(nx):
            v = visits[iy, ix]
            if v == 0:
                out[r, ix] = 127
            elif hits[iy, ix] > occ_thresh * v:
                out[r, ix] = 0
            else:
                out[r, ix] = 255
    return out


@nb.njit(cache=True)
def _copy_tiles(src, dst, differ, th, tw):
    """Copy the ``th x tw`` blocks of 2-D ``src`` flagged in ``differ`` to ``dst``."""
    ny, nx = src.shape
    for ty in range(differ.shape[0]):
        for tx in range(differ.shape[1]):
            if differ[ty, tx]:
                y0, y1 = ty * th, min(ty * th + th, ny)
                x0, x1 = tx * tw, min(tx * tw + tw, nx)
                dst[y0:y1, x0:x1] = src[y0:y1, x0:x1]


#: Side (cells) of the blocks that :meth:`CountGrid.copy` compares and copies.
TILE = 32
_next_tile_id = [1]  # ids are unique in the process: equal ids mean equal contents


def _fresh_tile_ids(n_rows: int, n_cols: int) -> np.ndarray:
    n = n_rows * n_cols
    start = _next_tile_id[0]
    _next_tile_id[0] += n
    return np.arange(start, start + n, dtype=np.int64).reshape(n_rows, n_cols)


# ------------------------------------------------------------------------ containers
class CountGrid:
    """One GMapping occupancy grid (hits, visits, accumulated hit positions) that grows.

    Parameters
    ----------
    shape : (ny, nx)
    x0, y0 : float
        World corner of cell ``(0, 0)``.
    delta : float
        Cell size in metres (GMapping's ``delta``).
    """

    __slots__ = ("hits", "visits", "sx", "sy", "mean", "x0", "y0", "delta", "tile_id")

    def __init__(self, shape: tuple[int, int], x0: float, y0: float, delta: float):
        self.hits = np.zeros(shape, np.int32)
        self.visits = np.zeros(shape, np.int32)
        self.sx = np.zeros(shape, np.float32)
        self.sy = np.zeros(shape, np.float32)
        self.mean = np.full((*shape, 2), np.nan, np.float32)
        self.x0 = float(x0)
        self.y0 = float(y0)
        self.delta = float(delta)
        self._new_tile_ids()

    def _new_tile_ids(self) -> None:
        """Fresh content ids for every :data:`TILE` x :data:`TILE` block.

        A block's id changes whenever a scan may have written into it, and is
        handed on by copying, so two grids whose blocks carry the same id hold the
        same contents there: :meth:`copy` copies only the blocks that differ.
        """
        ny, nx = self.shape
        self.tile_id = _fresh_tile_ids(-(-ny // TILE), -(-nx // TILE))

    @classmethod
    def around(cls, x: float, y: float, half_size: float, delta: float) -> CountGrid:
        """A square grid of side ``2 * half_size`` metres centred on ``(x, y)``.

        Parameters
        ----------
        x, y : float
            Centre, metres.
        half_size : float
            Half the side, metres.
        delta : float
            Cell size, metres.

        Returns
        -------
        CountGrid
        """
        n = int(math.ceil(2 * half_size / delta))
        return cls((n, n), x - n * delta / 2, y - n * delta / 2, delta)

    def copy(self, out: CountGrid | None = None) -> CountGrid:
        """A copy; with ``out`` (a grid no longer needed) into its arrays when the
        shapes match, which saves allocating (and page-faulting) new ones.

        Into ``out``, only the blocks whose content ids differ are copied: after a
        resampling, a dropped particle and the one copied into its grid share most
        of their history, and a scan touches only the blocks within the usable range
        (measured: about a fifth of the blocks of a 7-minute run's grids differ).

        Parameters
        ----------
        out : CountGrid, optional
            A grid whose arrays may be reused.

        Returns
        -------
        CountGrid
        """
        if out is self:
            return self
        if out is None or out.shape != self.shape or out.x0 != self.x0 or out.y0 != self.y0:
            new = CountGrid.__new__(CountGrid)
            new.hits = self.hits.copy()
            new.visits = self.visits.copy()
            new.sx = self.sx.copy()
            new.sy = self.sy.copy()
            new.mean = self.mean.copy()
            new.tile_id = self.tile_id.copy()
        else:
            new = out
            differ = new.tile_id != self.tile_id
            for name in ("hits", "visits", "sx", "sy"):
                _copy_tiles(getattr(self, name), getattr(new, name), differ, TILE, TILE)
            ny, nx = self.shape  # (ny, nx, 2) seen as (ny, 2 nx)
            _copy_tiles(
                self.mean.reshape(ny, 2 * nx), new.mean.reshape(ny, 2 * nx), differ, TILE, 2 * TILE
            )
            new.tile_id[...] = self.tile_id
        new.x0, new.y0, new.delta = self.x0, self.y0, self.delta
        return new

    @property
    def shape(self) -> tuple[int, int]:
        return self.visits.shape  # type: ignore[return-value]

    def arrays(self):
        """``(hits, visits, sx, sy, mean, x0, y0, delta)``: leading arguments of the update.

        Returns
        -------
        tuple
        """
        return self.hits, self.visits, self.sx, self.sy, self.mean, self.x0, self.y0, self.delta

    def match_arrays(self):
        """``(mean, x0, y0, delta)``: leading arguments of the scan-score kernels.

        ``mean[iy, ix]`` is the mean hit position of an occupied cell (hits/visits
        above GMapping's fullness threshold 0.1) and NaN elsewhere; it is kept up to
        date by the map update, so the matcher reads one compact array.

        Returns
        -------
        tuple
        """
        return self.mean, self.x0, self.y0, self.delta

    def extent(self) -> tuple[float, float, float, float]:
        """World ``(xmin, xmax, ymin, ymax)`` covered by the grid.

        Returns
        -------
        (xmin, xmax, ymin, ymax) : float
        """
        ny, nx = self.shape
        return self.x0, self.x0 + nx * self.delta, self.y0, self.y0 + ny * self.delta

    def padding_for(self, xmin: float, xmax: float, ymin: float, ymax: float, margin: float):
        """Cells to add ``(left, right, bottom, top)`` so the box plus ``margin`` fits, or None.

        A side that must grow grows by at least a quarter of the grid's size, so
        growth (a copy of every array) stays rare.

        Parameters
        ----------
        xmin, xmax, ymin, ymax : float
            Box to fit, metres.
        margin : float
            Extra room, metres.

        Returns
        -------
        (left, right, bottom, top) or None
        """
        gx0, gx1, gy0, gy1 = self.extent()
        need = (
            gx0 - (xmin - margin),
            xmax + margin - gx1,
            gy0 - (ymin - margin),
            ymax + margin - gy1,
        )
        if max(need) <= 0:
            return None
        step = max(2 * margin, 0.25 * max(gx1 - gx0, gy1 - gy0))
        return tuple(int(math.ceil(max(n, step) / self.delta)) if n > 0 else 0 for n in need)

    def pad(self, left: int, right: int, bottom: int, top: int) -> None:
        """Grow in place by whole cells (rows ``iy`` grow upwards with y).

        Parameters
        ----------
        left, right, bottom, top : int
            Cells added on each side.
        """
        widths = ((bottom, top), (left, right))
        self.hits = np.pad(self.hits, widths)
        self.visits = np.pad(self.visits, widths)
        self.sx = np.pad(self.sx, widths)
        self.sy = np.pad(self.sy, widths)
        self.mean = np.pad(self.mean, (*widths, (0, 0)), constant_values=np.nan)
        self.x0 -= left * self.delta
        self.y0 -= bottom * self.delta
        self._new_tile_ids()  # the blocks moved

    def register_scan(
        self,
        laser_pose,
        ranges: np.ndarray,
        angles: np.ndarray,
        usable_range: float,
        max_range: float = np.inf,
        no_return_free: bool = False,
    ) -> None:
        """Integrate a scan from the world laser pose ``(x, y, theta)`` (grows if needed).

        Parameters
        ----------
        laser_pose : (x, y, theta)
            World pose of the laser.
        ranges, angles : float arrays
            The scan's readings (metres) and beam angles in the laser frame.
        usable_range : float
            GMapping's ``maxUrange``.
        max_range : float
            GMapping's ``maxRange``.
        no_return_free : bool
            Let no-return beams clear up to ``usable_range``.
        """
        lx, ly, lt = (float(v) for v in laser_pose)
        r = np.asarray(ranges, np.float64)
        a = np.asarray(angles, np.float64)
        fin = np.where(np.isfinite(r), r, usable_range if no_return_free else 0.0)
        reach = min(usable_range, float(np.max(fin, initial=0.0)))
        pad = self.padding_for(lx, lx, ly, ly, reach + 2 * self.delta)
        if pad is not None:
            self.pad(*pad)
        register_scan(
            *self.arrays(),
            lx,
            ly,
            lt,
            r,
            a,
            float(usable_range),
            float(max_range),
            bool(no_return_free),
        )
        # every cell written lies within ``reach`` of the laser: new ids for those blocks
        k = reach / self.delta + 2
        cx = (lx - self.x0) / self.delta
        cy = (ly - self.y0) / self.delta
        nty, ntx = self.tile_id.shape
        tx0, tx1 = max(0, int((cx - k) // TILE)), min(ntx, int((cx + k) // TILE) + 1)
        ty0, ty1 = max(0, int((cy - k) // TILE)), min(nty, int((cy + k) // TILE) + 1)
        if tx1 > tx0 and ty1 > ty0:
            self.tile_id[ty0:ty1, tx0:tx1] = _fresh_tile_ids(ty1 - ty0, tx1 - tx0)

    def to_occupancy_map(self, occ_thresh: float = 0.25, meta: dict | None = None) -> OccupancyMap:
        """The ternary map (GMapping/slam_gmapping rule: occupied when hits/visits > occ_thresh).

        Parameters
        ----------
        occ_thresh : float
            Hit ratio above which a visited cell is occupied.
        meta : dict, optional
            Copied into the map.

        Returns
        -------
        OccupancyMap
        """
        data = occupancy_from_counts(self.hits, self.visits, float(occ_thresh))
        return OccupancyMap(data, self.delta, (self.x0, self.y0, 0.0), dict(meta or {}))


def likelihood_field(occupied: np.ndarray, delta: float, sigma: float) -> np.ndarray:
    """Likelihood field ``exp(-d^2 / (2 sigma^2))`` of the distance ``d`` (m) to the nearest hit.

    ``occupied`` is a boolean grid; the distance transform is OpenCV's exact
    Euclidean one (``cv2.DIST_L2``, ``DIST_MASK_PRECISE``). Returns float32 in
    ``[0, 1]``, 1 on occupied cells.

    Parameters
    ----------
    occupied : (H, W) bool array
        Hit cells.
    delta : float
        Cell size, metres.
    sigma : float
        Standard deviation, metres.

    Returns
    -------
    (H, W) float32 array

    Examples
    --------
    >>> occ = np.zeros((5, 5), bool); occ[2, 2] = True
    >>> f = likelihood_field(occ, 0.1, 0.1)
    >>> float(f[2, 2]), round(float(f[2, 3]), 3)
    (1.0, 0.607)
    """
    src = np.where(np.asarray(occupied, bool), 0, 255).astype(np.uint8)
    if not (src == 0).any():
        return np.zeros(src.shape, np.float32)
    d = cv2.distanceTransform(src, cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * float(delta)
    return np.exp(-(d * d) / (2.0 * sigma * sigma)).astype(np.float32)


#: The three cell values, re-exported for backends.
CELL_VALUES = (OCCUPIED, UNKNOWN, FREE)
