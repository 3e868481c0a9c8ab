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
    "TilePool",
    "scan_tiles",
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


#: Tiles are ``TILE x TILE`` cells; ``TILE = 2 ** TILE_SHIFT``.
TILE_SHIFT = 6
TILE = 1 << TILE_SHIFT
_MASK = TILE - 1
#: Bytes of one tile: hits, visits (int32), sx, sy (float32), mean (2 float32).
TILE_BYTES = TILE * TILE * (4 + 4 + 4 + 4 + 8)


# ----------------------------------------------------------------------------- kernels
@nb.njit(cache=True, inline="always")
def _tile_at(table, tx0, ty0, x, y):
    """Tile id holding global cell ``(x, y)`` (-1: none); ``>>`` floors negative cells."""
    ty = (y >> TILE_SHIFT) - ty0
    tx = (x >> TILE_SHIFT) - tx0
    if ty < 0 or tx < 0 or ty >= table.shape[0] or tx >= table.shape[1]:
        return -1
    return table[ty, tx]


@nb.njit(cache=True)
def _bresenham_update(
    table, tx0, ty0, hits, visits, sx, sy, mean, x0, y0, x1, y1, hit, hx, hy, stop_at_wall
):
    """Walk the Bresenham line (x0,y0)->(x1,y1) of global cells; visit every cell but the last.

    The last cell gets a hit (with the world endpoint ``hx, hy``) when ``hit``.
    Cells without a tile are ignored (:meth:`CountGrid.register_scan` gives every
    cell a scan reaches a tile of its own first). With ``stop_at_wall`` the walk ends
    at the first occupied cell (a beam without a return cannot have passed a wall).
    """
    dx = abs(x1 - x0)
    dy = -abs(y1 - y0)
    stx = 1 if x0 < x1 else -1
    sty = 1 if y0 < y1 else -1
    err = dx + dy
    x, y = x0, y0
    while True:
        if x == x1 and y == y1:
            break
        t = _tile_at(table, tx0, ty0, x, y)
        if t >= 0:
            lx = x & _MASK
            ly = y & _MASK
            if stop_at_wall and mean[t, ly, lx, 0] == mean[t, ly, lx, 0]:
                return
            visits[t, ly, lx] += 1
            if hits[t, ly, lx] <= FULLNESS_THRESHOLD * visits[t, ly, lx]:
                mean[t, ly, lx, 0] = np.nan
        e2 = 2 * err
        if e2 >= dy:
            err += dy
            x += stx
        if e2 <= dx:
            err += dx
            y += sty
    t = _tile_at(table, tx0, ty0, x1, y1)
    if hit and t >= 0:
        lx = x1 & _MASK
        ly = y1 & _MASK
        visits[t, ly, lx] += 1
        hits[t, ly, lx] += 1
        sx[t, ly, lx] += hx
        sy[t, ly, lx] += hy
        h = hits[t, ly, lx]
        if h > FULLNESS_THRESHOLD * visits[t, ly, lx]:
            mean[t, ly, lx, 0] = sx[t, ly, lx] / h
            mean[t, ly, lx, 1] = sy[t, ly, lx] / h
        else:
            mean[t, ly, lx, 0] = np.nan


@nb.njit(cache=True, inline="always")
def _beam_end(lx, ly, lt, r, a, usable_range, max_range, no_return_free):
    """``(ok, hit, hx, hy, no_return)`` of one beam, GMapping's ``registerScan`` rules."""
    if not (r > 0.0):
        return False, False, 0.0, 0.0, False
    no_return = r > max_range
    if no_return:
        if not no_return_free:
            return False, False, 0.0, 0.0, False
        r = usable_range
    hit = True
    if r >= usable_range:
        r = usable_range
        hit = False
    b = lt + a
    return True, hit, lx + r * math.cos(b), ly + r * math.sin(b), no_return


@nb.njit(cache=True)
def register_scan(
    table,
    tx0,
    ty0,
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
    table : (TY, TX) int32 array
        Tile ids of the grid (-1: no tile), see :class:`CountGrid`.
    tx0, ty0 : int
        Tile coordinates of ``table[0, 0]``.
    hits, visits : (P, TILE, TILE) int32 arrays
        Per-cell counts of every tile, updated in place.
    sx, sy : (P, TILE, TILE) float32 arrays
        Sums of the hit points' world x and y per cell, updated in place.
    mean : (P, TILE, TILE, 2) float32 array
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
        ok, hit, hx, hy, no_return = _beam_end(
            lx, ly, lt, ranges[i], angles[i], usable_range, max_range, no_return_free
        )
        if not ok:
            continue
        cx1 = int(math.floor((hx - gx0) / delta))
        cy1 = int(math.floor((hy - gy0) / delta))
        _bresenham_update(
            table, tx0, ty0, hits, visits, sx, sy, mean, cx0, cy0, cx1, cy1, hit, hx, hy, no_return
        )


@nb.njit(cache=True)
def scan_tiles(
    gx0, gy0, delta, lx, ly, lt, ranges, angles, usable_range, max_range, no_return_free, box
):
    """Global ``(ty, tx)`` of every tile :func:`register_scan` would write, sorted.

    The same beams and Bresenham lines as :func:`register_scan` (each line walked
    to its end: a no-return beam that stops at a wall asks for a tile or two more),
    within ``box`` metres of the laser (no beam reaches farther; cells past it are
    not marked).

    Returns
    -------
    (K, 2) int64 array
    """
    cx0 = int(math.floor((lx - gx0) / delta))
    cy0 = int(math.floor((ly - gy0) / delta))
    reach = int(math.ceil(box / delta)) + 2
    bx0 = (cx0 - reach) >> TILE_SHIFT
    by0 = (cy0 - reach) >> TILE_SHIFT
    nbx = ((cx0 + reach) >> TILE_SHIFT) - bx0 + 1
    nby = ((cy0 + reach) >> TILE_SHIFT) - by0 + 1
    mark = np.zeros((nby, nbx), np.bool_)
    for i in range(ranges.shape[0]):
        ok, hit, hx, hy, no_return = _beam_end(
            lx, ly, lt, ranges[i], angles[i], usable_range, max_range, no_return_free
        )
        if not ok:
            continue
        x1 = int(math.floor((hx - gx0) / delta))
        y1 = int(math.floor((hy - gy0) / delta))
        dx = abs(x1 - cx0)
        dy = -abs(y1 - cy0)
        stx = 1 if cx0 < x1 else -1
        sty = 1 if cy0 < y1 else -1
        err = dx + dy
        x, y = cx0, cy0
        while True:
            j = (y >> TILE_SHIFT) - by0
            i = (x >> TILE_SHIFT) - bx0
            if 0 <= j < nby and 0 <= i < nbx:
                mark[j, i] = True
            if x == x1 and y == y1:
                break
            e2 = 2 * err
            if e2 >= dy:
                err += dy
                x += stx
            if e2 <= dx:
                err += dx
                y += sty
    n = 0
    for j in range(nby):
        for i in range(nbx):
            n += mark[j, i]
    out = np.empty((n, 2), np.int64)
    k = 0
    for j in range(nby):
        for i in range(nbx):
            if mark[j, i]:
                out[k, 0] = j + by0
                out[k, 1] = i + bx0
                k += 1
    return out


@nb.njit(cache=True)
def _own_tiles(table, tx0, ty0, coords, refs, free, n_free, hits, visits, sx, sy, mean):
    """Give the grid of ``table`` a tile of its own at every ``coords`` (copy on write).

    A missing tile is taken from the ``free`` stack (``n_free[0]`` entries) and
    cleared; a tile shared with another grid (``refs > 1``) is copied into a fresh
    one. The caller makes sure the table covers ``coords`` and that the stack holds
    enough tiles.
    """
    for k in range(coords.shape[0]):
        ty = coords[k, 0] - ty0
        tx = coords[k, 1] - tx0
        t = table[ty, tx]
        if t >= 0 and refs[t] == 1:
            continue
        n_free[0] -= 1
        u = free[n_free[0]]
        if t < 0:
            hits[u] = 0
            visits[u] = 0
            sx[u] = 0.0
            sy[u] = 0.0
            mean[u] = np.nan
        else:
            hits[u] = hits[t]
            visits[u] = visits[t]
            sx[u] = sx[t]
            sy[u] = sy[t]
            mean[u] = mean[t]
            refs[t] -= 1
        refs[u] = 1
        table[ty, tx] = u


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
def _nearest_hit(table, tx0, ty0, mean, gx0, gy0, inv, free_back, hx, hy, ca, sa, kernel):
    """GMapping's kernel search for one endpoint ``(hx, hy)`` of a beam along ``(ca, sa)``.

    Among the ``(2 kernel + 1)^2`` cells around the endpoint, the occupied cell whose
    mean hit is nearest, provided the cell one step back along the beam
    (``delta * sqrt(2)``, GMapping's ``freeCellRatio``) is not occupied. Returns
    ``(d^2, mean_x, mean_y)``, ``d^2 = 1e30`` when nothing matched. A cell without a
    tile was never seen: not occupied. When the cells and their predecessors lie in
    one tile (most endpoints) the tile is looked up once.
    """
    ix = int(math.floor((hx - gx0) * inv))
    iy = int(math.floor((hy - gy0) * inv))
    fx = int(math.floor((hx - free_back * ca - gx0) * inv)) - ix
    fy = int(math.floor((hy - free_back * sa - gy0) * inv)) - iy
    best = 1e30
    bx = 0.0
    by = 0.0
    xlo = ix - kernel + min(fx, 0)
    xhi = ix + kernel + max(fx, 0)
    ylo = iy - kernel + min(fy, 0)
    yhi = iy + kernel + max(fy, 0)
    if (xlo >> TILE_SHIFT) == (xhi >> TILE_SHIFT) and (ylo >> TILE_SHIFT) == (yhi >> TILE_SHIFT):
        t = _tile_at(table, tx0, ty0, ix, iy)
        if t < 0:
            return best, bx, by
        oy = (iy >> TILE_SHIFT) << TILE_SHIFT
        ox = (ix >> TILE_SHIFT) << TILE_SHIFT
        for yy in range(-kernel, kernel + 1):
            cy = iy + yy - oy
            cfy = cy + fy
            for xx in range(-kernel, kernel + 1):
                cx = ix + xx - ox
                cfx = cx + fx
                # branch-free (the occupancy pattern is unpredictable, a mispredicted
                # branch costs more than the arithmetic): a cell that is not occupied
                # has a NaN mean, so its d2 is NaN and never below best; an occupied
                # predecessor (non-NaN) vetoes the cell
                mux = mean[t, cy, cx, 0]
                muy = mean[t, cy, cx, 1]
                pred = mean[t, cfy, cfx, 0]
                d2 = (hx - mux) * (hx - mux) + (hy - muy) * (hy - muy)
                take = (d2 < best) & (pred != pred)
                best = d2 if take else best
                bx = mux if take else bx
                by = muy if take else by
        return best, bx, by
    for yy in range(-kernel, kernel + 1):
        cy = iy + yy
        cfy = cy + fy
        for xx in range(-kernel, kernel + 1):
            cx = ix + xx
            cfx = cx + fx
            t = _tile_at(table, tx0, ty0, cx, cy)
            if t < 0:
                continue
            mux = mean[t, cy & _MASK, cx & _MASK, 0]
            muy = mean[t, cy & _MASK, cx & _MASK, 1]
            tf = _tile_at(table, tx0, ty0, cfx, cfy)
            pred = mean[tf, cfy & _MASK, cfx & _MASK, 0] if tf >= 0 else np.nan
            d2 = (hx - mux) * (hx - mux) + (hy - muy) * (hy - muy)
            take = (d2 < best) & (pred != pred)
            best = d2 if take else best
            bx = mux if take else bx
            by = muy if take else by
    return best, bx, by


@nb.njit(cache=True, fastmath=_FAST)
def _score_core(table, tx0, ty0, mean, gx0, gy0, delta, px, py, pt, beams, kernel, sigma, lsigma):
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
        best = _nearest_hit(
            table, tx0, ty0, mean, gx0, gy0, inv, free_back, hx, hy, ca, sa, kernel
        )[0]
        if best < 1e29:
            s += math.exp(-best / sigma)
            lik += -best / lsigma
            n += 1
        else:
            lik += no_hit
    return s, lik, n


@nb.njit(cache=True)
def gmapping_score(
    table, tx0, ty0, mean, gx0, gy0, delta, px, py, pt, off, ranges, angles, kernel, sigma, lsigma
):
    """GMapping's scan score and log-likelihood at one pose; see :func:`_score_core`.

    Parameters
    ----------
    table : (TY, TX) int32 array
        Tile ids of the grid (-1: no tile); tile ``table[ty, tx]`` holds the cells of
        tile ``(ty + ty0, tx + tx0)``, see :class:`CountGrid`.
    tx0, ty0 : int
        Tile coordinates of ``table[0, 0]``.
    mean : (P, TILE, TILE, 2) float array
        Mean hit point of each cell of each tile (NaN: none), GMapping's likelihood
        reference.
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
        table,
        tx0,
        ty0,
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
    table,
    tx0,
    ty0,
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
    table : (TY, TX) int32 array
        Tile ids of the grid (-1: no tile); tile ``table[ty, tx]`` holds the cells of
        tile ``(ty + ty0, tx + tx0)``, see :class:`CountGrid`.
    tx0, ty0 : int
        Tile coordinates of ``table[0, 0]``.
    mean : (P, TILE, TILE, 2) float array
        Mean hit point of each cell of each tile (NaN: none), GMapping's likelihood
        reference.
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
    cur = _score_core(
        table, tx0, ty0, mean, gx0, gy0, delta, cx, cy, ct, beams, kernel, sigma, 1.0
    )[0] - _prior_penalty(prior, cx, cy, ct)
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
                table,
                tx0,
                ty0,
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
    table,
    tx0,
    ty0,
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
    table : (TY, TX) int32 array
        Tile ids of the grid (-1: no tile); tile ``table[ty, tx]`` holds the cells of
        tile ``(ty + ty0, tx + tx0)``, see :class:`CountGrid`.
    tx0, ty0 : int
        Tile coordinates of ``table[0, 0]``.
    mean : (P, TILE, TILE, 2) float array
        Mean hit point of each cell of each tile (NaN: none), GMapping's likelihood
        reference.
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
        d2, mx[b], my[b] = _nearest_hit(
            table, tx0, ty0, mean, gx0, gy0, inv, free_back, hx, hy, ca, sa, kernel
        )
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
def _tiles_to_image(table, hits, visits, occ_thresh, out):
    """Write every tile of ``table`` into the image-order map ``out`` (rows flipped).

    ``out`` is ``(TY * TILE, TX * TILE)``, all unknown; cells follow
    :func:`occupancy_from_counts`.
    """
    h = out.shape[0]
    for ty in range(table.shape[0]):
        for tx in range(table.shape[1]):
            t = table[ty, tx]
            if t < 0:
                continue
            for ly in range(TILE):
                r = h - 1 - (ty * TILE + ly)
                for lx in range(TILE):
                    v = visits[t, ly, lx]
                    if v == 0:
                        continue
                    if hits[t, ly, lx] > occ_thresh * v:
                        out[r, tx * TILE + lx] = 0
                    else:
                        out[r, tx * TILE + lx] = 255


# ------------------------------------------------------------------------ containers
class TilePool:
    """Storage of ``TILE x TILE``-cell tiles shared by the grids of one mapper.

    Tile ``t`` is ``hits[t]``, ``visits[t]``, ``sx[t]``, ``sy[t]`` and ``mean[t]``;
    ``refs[t]`` counts the grids holding it (0: free, on the ``free`` stack). Grids
    share tiles after a copy and take a tile of their own before writing into a
    shared one (copy on write, as GMapping's ``HierarchicalArray2D`` shares its
    patches between particles). The arrays grow in place (``ndarray.resize``, a
    ``realloc``: the old contents are not copied into a second block).

    Parameters
    ----------
    capacity : int
        Tiles allocated at first.

    Examples
    --------
    >>> pool = TilePool(4)
    >>> pool.reserve(6); pool.capacity >= 6, pool.used
    (True, 0)
    """

    def __init__(self, capacity: int = 64):
        c = max(1, int(capacity))
        self.hits = np.zeros((c, TILE, TILE), np.int32)
        self.visits = np.zeros((c, TILE, TILE), np.int32)
        self.sx = np.zeros((c, TILE, TILE), np.float32)
        self.sy = np.zeros((c, TILE, TILE), np.float32)
        self.mean = np.zeros((c, TILE, TILE, 2), np.float32)
        self.refs = np.zeros(c, np.int32)
        self.free = np.arange(c - 1, -1, -1, dtype=np.int32)  # popped from the end
        self.n_free = np.array([c], np.int64)
        #: Most tiles in use at once.
        self.peak = 0

    @property
    def capacity(self) -> int:
        return int(self.refs.shape[0])

    @property
    def used(self) -> int:
        """Tiles held by some grid."""
        return self.capacity - int(self.n_free[0])

    def nbytes(self) -> int:
        """Bytes of the tile arrays (allocated, used or not)."""
        return self.capacity * TILE_BYTES

    def reserve(self, n: int) -> None:
        """Make sure ``n`` tiles are free (grow by at least a quarter when not).

        Parameters
        ----------
        n : int
            Free tiles needed.
        """
        if int(self.n_free[0]) >= n:
            return
        old = self.capacity
        new = max(old + n - int(self.n_free[0]), old + old // 4, old + 16)
        for name in ("hits", "visits", "sx", "sy", "mean"):
            a = getattr(self, name)
            a.resize((new, *a.shape[1:]), refcheck=False)  # realloc: no second copy
        self.refs = np.concatenate([self.refs, np.zeros(new - old, np.int32)])
        k = int(self.n_free[0])
        free = np.empty(new, np.int32)
        free[: new - old] = np.arange(new - 1, old - 1, -1, dtype=np.int32)
        free[new - old : new - old + k] = self.free[:k]
        self.free = free
        self.n_free[0] = k + new - old

    def release(self, table: np.ndarray) -> None:
        """Drop one holder of every tile of ``table``; tiles nobody holds are freed.

        Parameters
        ----------
        table : int array
            A grid's tile ids (-1: none); each id appears once.
        """
        ids = table[table >= 0]
        self.refs[ids] -= 1
        gone = ids[self.refs[ids] == 0]
        k = int(self.n_free[0])
        self.free[k : k + gone.size] = gone[::-1]
        self.n_free[0] = k + gone.size


class CountGrid:
    """One GMapping occupancy grid (hits, visits, accumulated hit positions) that grows
    as the robot goes: tiles of ``TILE x TILE`` cells allocated on first touch.

    Cell ``(ix, iy)`` covers ``[x0 + ix delta, x0 + (ix + 1) delta)`` in x (likewise
    in y); indices may be negative, the origin never moves. Tile ``(ty, tx)`` holds
    cells ``ty * TILE <= iy < (ty + 1) * TILE`` (likewise in x); ``table[ty - ty0,
    tx - tx0]`` is its id in the :class:`TilePool` (-1: never touched, all unknown).
    Grids made by :meth:`copy` share their tiles until one of them writes (copy on
    write), so the particles of a filter hold their common history once. Memory is
    about :data:`TILE_BYTES` per tile touched, whatever the extent.

    Parameters
    ----------
    shape : (ny, nx)
        Cells the tile table covers at first (it grows when a scan reaches past it).
    x0, y0 : float
        World corner of cell ``(0, 0)``.
    delta : float
        Cell size in metres (GMapping's ``delta``).
    pool : TilePool, optional
        Tile storage to share (default: a pool of its own).
    """

    __slots__ = ("pool", "table", "tx0", "ty0", "x0", "y0", "delta")

    def __init__(
        self,
        shape: tuple[int, int],
        x0: float,
        y0: float,
        delta: float,
        pool: TilePool | None = None,
    ):
        ny, nx = (max(1, int(v)) for v in shape)
        self.pool = pool if pool is not None else TilePool()
        self.table = np.full((-(-ny // TILE), -(-nx // TILE)), -1, np.int32)
        self.tx0 = 0
        self.ty0 = 0
        self.x0 = float(x0)
        self.y0 = float(y0)
        self.delta = float(delta)

    @classmethod
    def around(
        cls, x: float, y: float, half_size: float, delta: float, pool: TilePool | None = None
    ) -> CountGrid:
        """A grid whose origin puts ``(x, y)`` at the centre of a square of side ``2 * half_size``.

        Parameters
        ----------
        x, y : float
            Centre, metres.
        half_size : float
            Half the side, metres.
        delta : float
            Cell size, metres.
        pool : TilePool, optional
            Tile storage to share.

        Returns
        -------
        CountGrid
        """
        n = int(math.ceil(2 * half_size / delta))
        return cls((n, n), x - n * delta / 2, y - n * delta / 2, delta, pool)

    def copy(self) -> CountGrid:
        """A copy sharing every tile with this grid until either writes (copy on write).

        Returns
        -------
        CountGrid
        """
        new = CountGrid.__new__(CountGrid)
        new.pool = self.pool
        new.table = self.table.copy()
        ids = self.table[self.table >= 0]
        self.pool.refs[ids] += 1
        new.tx0, new.ty0 = self.tx0, self.ty0
        new.x0, new.y0, new.delta = self.x0, self.y0, self.delta
        return new

    def release(self) -> None:
        """Give the tiles back to the pool (the grid is empty afterwards)."""
        self.pool.release(self.table)
        self.table[...] = -1

    @property
    def shape(self) -> tuple[int, int]:
        """Cells the tile table spans, ``(ny, nx)``."""
        return self.table.shape[0] * TILE, self.table.shape[1] * TILE

    @property
    def n_tiles(self) -> int:
        """Tiles this grid holds (shared or not)."""
        return int((self.table >= 0).sum())

    def arrays(self):
        """``(table, tx0, ty0, hits, visits, sx, sy, mean, x0, y0, delta)``: leading
        arguments of :func:`register_scan`.

        Returns
        -------
        tuple
        """
        p = self.pool
        return (
            self.table, self.tx0, self.ty0, p.hits, p.visits, p.sx, p.sy, p.mean,
            self.x0, self.y0, self.delta,
        )  # fmt: skip

    def match_arrays(self):
        """``(table, tx0, ty0, mean, x0, y0, delta)``: leading arguments of the scan-score kernels.

        ``mean[t, ly, lx]`` is the mean hit position of an occupied cell (hits/visits
        above GMapping's fullness threshold 0.1) and NaN elsewhere; it is kept up to
        date by the map update, so the matcher reads one compact array.

        Returns
        -------
        tuple
        """
        return self.table, self.tx0, self.ty0, self.pool.mean, self.x0, self.y0, self.delta

    def extent(self) -> tuple[float, float, float, float]:
        """World ``(xmin, xmax, ymin, ymax)`` spanned by the tile table.

        Returns
        -------
        (xmin, xmax, ymin, ymax) : float
        """
        ny, nx = self.shape
        d = self.delta
        xmin = self.x0 + self.tx0 * TILE * d
        ymin = self.y0 + self.ty0 * TILE * d
        return xmin, xmin + nx * d, ymin, ymin + ny * d

    def _cover(self, ty_lo: int, ty_hi: int, tx_lo: int, tx_hi: int) -> None:
        """Widen the tile table to tiles ``ty_lo..ty_hi`` x ``tx_lo..tx_hi`` (global)."""
        nty, ntx = self.table.shape
        if ty_lo >= self.ty0 and tx_lo >= self.tx0:
            if ty_hi < self.ty0 + nty and tx_hi < self.tx0 + ntx:
                return
        step_y = max(4, nty // 4)
        step_x = max(4, ntx // 4)
        y0 = min(self.ty0, ty_lo - step_y) if ty_lo < self.ty0 else self.ty0
        x0 = min(self.tx0, tx_lo - step_x) if tx_lo < self.tx0 else self.tx0
        y1 = ty_hi + step_y if ty_hi >= self.ty0 + nty else self.ty0 + nty - 1
        x1 = tx_hi + step_x if tx_hi >= self.tx0 + ntx else self.tx0 + ntx - 1
        table = np.full((y1 - y0 + 1, x1 - x0 + 1), -1, np.int32)
        table[self.ty0 - y0 : self.ty0 - y0 + nty, self.tx0 - x0 : self.tx0 - x0 + ntx] = self.table
        self.table, self.ty0, self.tx0 = table, y0, x0

    def register_scan(
        self,
        laser_pose,
        ranges: np.ndarray,
        angles: np.ndarray,
        usable_range: float,
        max_range: float = np.inf,
        no_return_free: bool = False,
    ) -> None:
        """Integrate a scan from the world laser pose ``(x, y, theta)``.

        The tiles the beams reach (:func:`scan_tiles`) are allocated, or copied when
        shared with another grid, before :func:`register_scan` writes into them.

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
        args = (float(usable_range), float(max_range), bool(no_return_free))
        box = float(usable_range)
        if not math.isfinite(box):  # no beam reaches past the farthest finite reading
            box = float(np.max(r[np.isfinite(r)], initial=0.0))
        coords = scan_tiles(self.x0, self.y0, self.delta, lx, ly, lt, r, a, *args, box)
        if coords.shape[0] == 0:
            return
        lo = coords.min(0)
        hi = coords.max(0)
        self._cover(int(lo[0]), int(hi[0]), int(lo[1]), int(hi[1]))
        p = self.pool
        p.reserve(coords.shape[0])
        _own_tiles(
            self.table, self.tx0, self.ty0, coords, p.refs, p.free, p.n_free,
            p.hits, p.visits, p.sx, p.sy, p.mean,
        )  # fmt: skip
        p.peak = max(p.peak, p.used)
        register_scan(*self.arrays(), lx, ly, lt, r, a, *args)

    def counts(self) -> tuple[np.ndarray, np.ndarray]:
        """Dense ``(hits, visits)`` over the tile table (row 0 = smallest y), for checks.

        Returns
        -------
        hits, visits : (ny, nx) int32 arrays
        """
        ny, nx = self.shape
        out = []
        for name in ("hits", "visits"):
            src = getattr(self.pool, name)
            d = np.zeros((ny, nx), np.int32)
            for ty, tx in zip(*np.nonzero(self.table >= 0), strict=True):
                d[ty * TILE : (ty + 1) * TILE, tx * TILE : (tx + 1) * TILE] = src[
                    self.table[ty, tx]
                ]
            out.append(d)
        return out[0], out[1]

    def to_occupancy_map(self, occ_thresh: float = 0.25, meta: dict | None = None) -> OccupancyMap:
        """The ternary map (GMapping/slam_gmapping rule: occupied when hits/visits > occ_thresh).

        The map spans the tiles touched plus one unknown tile on every side (ROS
        origin: the world corner of its lower-left pixel).

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
        rows, cols = np.nonzero(self.table >= 0)
        if rows.size == 0:
            rows = cols = np.zeros(1, int)
        y0, y1 = int(rows.min()) - 1, int(rows.max()) + 2
        x0, x1 = int(cols.min()) - 1, int(cols.max()) + 2
        sub = np.full((y1 - y0, x1 - x0), -1, np.int32)
        ys0, xs0 = max(y0, 0), max(x0, 0)
        ys1, xs1 = min(y1, self.table.shape[0]), min(x1, self.table.shape[1])
        sub[ys0 - y0 : ys1 - y0, xs0 - x0 : xs1 - x0] = self.table[ys0:ys1, xs0:xs1]
        data = np.full(((y1 - y0) * TILE, (x1 - x0) * TILE), 127, np.uint8)
        _tiles_to_image(sub, self.pool.hits, self.pool.visits, float(occ_thresh), data)
        d = self.delta
        origin = (
            self.x0 + (self.tx0 + x0) * TILE * d,
            self.y0 + (self.ty0 + y0) * TILE * d,
            0.0,
        )
        return OccupancyMap(data, d, origin, dict(meta or {}))


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
