"""Probabilistic roadmap over a floor plan's free space (thesis section 3.2, Fig. 3.3, ref. [54]).

The roadmap follows Kavraki et al. [54]: random nodes in the free space that keep a
clearance of the robot radius from every wall, each joined to its ``k`` nearest
neighbours when the straight segment between them keeps that clearance too; paths are
shortest paths in that graph (:func:`scipy.sparse.csgraph.dijkstra`). Uniform sampling
rarely puts a node inside a narrow door, so nodes are also placed along the skeleton
(medial axis) of the clearance region every ``skeleton_step`` metres: every door the
robot fits through then has nodes in it and is passable.

The roadmap is built on a working grid of at least 5 cm per pixel (the plan is
reduced by an integer factor, a cell is free only if all its plan pixels are), so that
a 1600 x 1600 plan costs no more than a 256 x 256 one. Node coordinates are stored in
*plan pixel* coordinates ``(x = column, y = row)``, integer values at pixel centres.

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> data = np.zeros((60, 100), np.uint8); data[5:55, 5:95] = 255
>>> plan = OccupancyMap(data, resolution=0.05)
>>> rm = build_roadmap(plan, robot_radius=0.15, rng=np.random.default_rng(0))
>>> path = shortest_path(rm, (10.0, 10.0), (90.0, 50.0))   # pixel (x, y)
>>> bool(np.allclose(path[0], (10, 10)) and np.allclose(path[-1], (90, 50)))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.spatial import cKDTree
from skimage.morphology import skeletonize

from ..core.errors import InputError
from ..core.grid import OccupancyMap

__all__ = [
    "Roadmap",
    "build_roadmap",
    "shortest_path",
    "path_through",
    "random_start_goal",
    "random_tour",
    "segments_clear",
    "shortcut_path",
]

#: Coarsest plan resolution the roadmap works at [m/px].
WORK_RESOLUTION = 0.05


@dataclass
class Roadmap:
    """A roadmap: nodes, edges and the masks they were checked against.

    Attributes
    ----------
    nodes : (N, 2) float array
        Node positions in plan pixels ``(x = column, y = row)``.
    edges : (M, 2) int array
        Node index pairs joined by collision-free segments.
    graph : scipy.sparse.csr_matrix
        Symmetric (N, N) matrix of edge lengths in plan pixels.
    safe : (h, w) bool array
        Working-grid cells whose centre is at least the robot radius from any non-free cell.
    free : (h, w) bool array
        Working-grid free cells.
    factor : int
        Plan pixels per working-grid cell.
    """

    nodes: np.ndarray
    edges: np.ndarray
    graph: csr_matrix
    safe: np.ndarray
    free: np.ndarray
    factor: int

    def to_work(self, xy: np.ndarray) -> np.ndarray:
        """Plan pixel (x, y) -> working-grid continuous indices (x, y).

        Parameters
        ----------
        xy : (N, 2) array

        Returns
        -------
        (N, 2) float array
        """
        return (np.asarray(xy, float) - (self.factor - 1) / 2.0) / self.factor

    def to_plan(self, xy: np.ndarray) -> np.ndarray:
        """Working-grid indices (x, y) -> plan pixel (x, y).

        Parameters
        ----------
        xy : (N, 2) array

        Returns
        -------
        (N, 2) float array
        """
        return np.asarray(xy, float) * self.factor + (self.factor - 1) / 2.0


def _working_free(plan: OccupancyMap) -> tuple[np.ndarray, int]:
    factor = max(1, int(np.floor(WORK_RESOLUTION / plan.resolution + 1e-9)))
    free = plan.free
    if factor == 1:
        return free, 1
    h, w = free.shape
    hh, ww = -(-h // factor) * factor, -(-w // factor) * factor
    padded = np.zeros((hh, ww), bool)
    padded[:h, :w] = free
    return padded.reshape(hh // factor, factor, ww // factor, factor).all(axis=(1, 3)), factor


def segments_clear(mask: np.ndarray, a: np.ndarray, b: np.ndarray, step: float = 0.5) -> np.ndarray:
    """Whether straight segments ``a[i] -> b[i]`` (grid (x, y)) stay on True cells of ``mask``.

    Every segment is sampled every ``step`` cells (vectorised over all segments).

    Parameters
    ----------
    mask : (h, w) bool array
        Traversable cells.
    a, b : (S, 2) float arrays
        Segment ends in grid coordinates ``(x = column, y = row)``.
    step : float
        Sampling step along each segment, in cells.

    Returns
    -------
    (S,) bool array
        True where every sample of the segment lies on a True cell inside the grid.

    Examples
    --------
    >>> m = np.ones((5, 5), bool); m[:, 2] = False
    >>> segments_clear(m, np.array([[0., 0], [0, 0]]), np.array([[4., 0], [1, 4]])).tolist()
    [False, True]
    """
    a = np.atleast_2d(np.asarray(a, float))
    b = np.atleast_2d(np.asarray(b, float))
    if a.shape[0] == 0:
        return np.zeros(0, bool)
    length = np.hypot(*(b - a).T)
    n = np.maximum(np.ceil(length / step).astype(np.int64), 1) + 1
    seg = np.repeat(np.arange(a.shape[0]), n)
    start = np.cumsum(n) - n
    frac = (np.arange(seg.size) - np.repeat(start, n)) / np.repeat(n - 1, n)
    pts = a[seg] + (b - a)[seg] * frac[:, None]
    cols = np.floor(pts[:, 0] + 0.5).astype(np.int64)
    rows = np.floor(pts[:, 1] + 0.5).astype(np.int64)
    h, w = mask.shape
    inside = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
    ok = np.zeros(seg.size, bool)
    ok[inside] = mask[rows[inside], cols[inside]]
    bad = np.bincount(seg, weights=~ok, minlength=a.shape[0])
    return bad == 0


def build_roadmap(
    plan: OccupancyMap,
    *,
    robot_radius: float = 0.15,
    nodes_per_m2: float = 2.0,
    k: int = 10,
    skeleton_step: float = 0.4,
    rng: np.random.Generator,
) -> Roadmap:
    """Build a probabilistic roadmap of a plan's free space (ref. [54]).

    Parameters
    ----------
    plan : OccupancyMap
        The floor plan; only its free cells are traversable.
    robot_radius : float
        Clearance [m] every node and edge keeps from non-free cells.
    nodes_per_m2 : float
        Density of the uniformly drawn nodes over the clearance region.
    k : int
        Each node is tried against its ``k`` nearest neighbours.
    skeleton_step : float
        Spacing [m] of the extra nodes on the skeleton of the clearance region.
    rng : numpy.random.Generator
        Source of the random nodes.

    Returns
    -------
    Roadmap
        Nodes, collision-free edges and the masks they were checked against.

    Raises
    ------
    InputError
        If the plan has no free cell with the required clearance.
    """
    free, factor = _working_free(plan)
    if not free.any():
        raise InputError(None, "the plan has no free space")
    res = plan.resolution * factor
    clearance = ndimage.distance_transform_edt(free)
    safe = clearance * res > robot_radius
    if not safe.any():
        raise InputError(None, f"no free space is wider than the robot (radius {robot_radius:g} m)")
    safe_rc = np.argwhere(safe)
    area_m2 = safe_rc.shape[0] * res * res
    n_uniform = int(min(max(20, np.ceil(nodes_per_m2 * area_m2)), safe_rc.shape[0], 20000))
    pick = rng.choice(safe_rc.shape[0], size=n_uniform, replace=False)
    uniform = safe_rc[pick][:, ::-1].astype(float) + rng.uniform(-0.4, 0.4, (n_uniform, 2))
    # keep jittered nodes inside safe cells
    ui = np.floor(uniform + 0.5).astype(np.int64)
    uniform = np.where(safe[ui[:, 1], ui[:, 0]][:, None], uniform, safe_rc[pick][:, ::-1])
    skel = np.argwhere(skeletonize(safe))[:, ::-1].astype(float)
    if skel.shape[0]:
        step_px = max(1.0, skeleton_step / res)
        keys = np.floor(skel / step_px).astype(np.int64)
        _, first = np.unique(keys[:, 0] * 1_000_003 + keys[:, 1], return_index=True)
        skel = skel[np.sort(first)]
    nodes_w = np.vstack([uniform, skel])
    n = nodes_w.shape[0]
    kk = min(k + 1, n)
    tree = cKDTree(nodes_w)
    _, nbr = tree.query(nodes_w, k=kk)
    nbr = np.atleast_2d(nbr)
    i = np.repeat(np.arange(n), kk - 1)
    j = nbr[:, 1:].ravel()
    lo, hi = np.minimum(i, j), np.maximum(i, j)
    pairs = np.unique(np.stack([lo, hi], 1), axis=0)
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    ok = segments_clear(safe, nodes_w[pairs[:, 0]], nodes_w[pairs[:, 1]])
    edges = pairs[ok]
    nodes = nodes_w * factor + (factor - 1) / 2.0
    graph = _graph(nodes, edges, n)
    return Roadmap(nodes=nodes, edges=edges, graph=graph, safe=safe, free=free, factor=factor)


def _graph(nodes: np.ndarray, edges: np.ndarray, n: int) -> csr_matrix:
    w = np.hypot(*(nodes[edges[:, 0]] - nodes[edges[:, 1]]).T)
    w = np.maximum(w, 1e-9)
    g = coo_matrix(
        (np.concatenate([w, w]), (np.concatenate(edges.T[::-1]), np.concatenate(edges.T))),
        shape=(n, n),
    )
    return g.tocsr()


def _attach(rm: Roadmap, p: np.ndarray, k: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Roadmap nodes reachable from plan pixel ``p`` by a straight free segment, and lengths."""
    nodes_w = rm.to_work(rm.nodes)
    pw = rm.to_work(p[None])[0]
    kk = min(k, nodes_w.shape[0])
    dist, idx = cKDTree(nodes_w).query(pw, k=kk)
    idx = np.atleast_1d(idx)
    ok = segments_clear(rm.free, np.repeat(pw[None], idx.size, 0), nodes_w[idx])
    idx = idx[ok]
    return idx, np.hypot(*(rm.nodes[idx] - p).T)


def shortest_path(rm: Roadmap, start: tuple[float, float], goal: tuple[float, float]) -> np.ndarray:
    """Shortest roadmap path between two plan pixels ``(x, y)``; returns (P, 2) plan pixels.

    Start and goal are joined to nearby nodes by straight segments through free cells
    (they may lie closer to a wall than the robot radius). Raises ``InputError`` when no
    path exists. The path is shortened by :func:`shortcut_path`.

    Parameters
    ----------
    rm : Roadmap
        From :func:`build_roadmap`.
    start, goal : (x, y)
        Plan pixels (column, row), continuous.

    Returns
    -------
    (P, 2) float array
        Waypoints in plan pixels from ``start`` to ``goal``.

    Raises
    ------
    InputError
        Start or goal cannot reach the roadmap, or no path joins them.

    Examples
    --------
    >>> from map2map.core.grid import OccupancyMap
    >>> data = np.zeros((60, 100), np.uint8); data[5:55, 5:95] = 255
    >>> rm = build_roadmap(OccupancyMap(data, 0.05), rng=np.random.default_rng(0))
    >>> path = shortest_path(rm, (15.0, 30.0), (85.0, 30.0))
    >>> path[0].tolist(), path[-1].tolist()
    ([15.0, 30.0], [85.0, 30.0])
    """
    s = np.asarray(start, float)
    g = np.asarray(goal, float)
    if np.allclose(s, g):
        return np.stack([s, g])
    sw, gw = rm.to_work(np.stack([s, g]))
    if segments_clear(rm.safe, sw[None], gw[None])[0]:
        return np.stack([s, g])
    n = rm.nodes.shape[0]
    si, sd = _attach(rm, s)
    gi, gd = _attach(rm, g)
    if si.size == 0 or gi.size == 0:
        raise InputError(None, "not connected")
    rows = np.concatenate([np.full(si.size, n), gi])
    cols = np.concatenate([si, np.full(gi.size, n + 1)])
    extra = coo_matrix((np.concatenate([sd, gd]), (rows, cols)), shape=(n + 2, n + 2))
    big = rm.graph.copy()
    big.resize((n + 2, n + 2))
    big = (big + extra + extra.T).tocsr()
    dist, pred = dijkstra(big, directed=False, indices=n, return_predecessors=True)
    if not np.isfinite(dist[n + 1]):
        raise InputError(None, "not connected")
    order = [n + 1]
    while order[-1] != n:
        order.append(pred[order[-1]])
    pts = np.vstack([rm.nodes, s[None], g[None]])[order[::-1]]
    return shortcut_path(rm, pts)


def shortcut_path(rm: Roadmap, path: np.ndarray) -> np.ndarray:
    """Greedy line-of-sight shortening: jump to the farthest waypoint still reachable.

    Inner waypoints are tested against the clearance mask, so the result keeps the
    robot-radius clearance wherever the roadmap did.

    Parameters
    ----------
    rm : Roadmap
        The roadmap whose masks the shortcuts are checked against.
    path : (P, 2) float array
        Waypoints in plan pixels.

    Returns
    -------
    (Q, 2) float array
        A subsequence of ``path`` (first and last kept), Q <= P.
    """
    if path.shape[0] <= 2:
        return path
    pw = rm.to_work(path)
    out = [0]
    i = 0
    last = path.shape[0] - 1
    while i < last:
        cand = np.arange(i + 1, last + 1)
        ok = segments_clear(rm.safe, np.repeat(pw[i][None], cand.size, 0), pw[cand])
        ok |= cand == i + 1  # roadmap edges (and start/goal legs) were checked already
        j = int(cand[np.flatnonzero(ok)[-1]])
        out.append(j)
        i = j
    return path[out]


def path_through(rm: Roadmap, waypoints: np.ndarray, names: list[str] | None = None) -> np.ndarray:
    """Shortest path visiting plan pixels ``waypoints`` (W, 2) in order.

    ``names`` (e.g. the world coordinates as typed by the user) are used in the error
    message when two consecutive waypoints are not connected.

    Parameters
    ----------
    rm : Roadmap
        From :func:`build_roadmap`.
    waypoints : (W, 2) float array
        Plan pixels ``(x, y)`` to visit in order, W >= 2.
    names : list of str, optional
        How each waypoint is named in error messages.

    Returns
    -------
    (P, 2) float array
        The concatenated shortest paths, in plan pixels.

    Raises
    ------
    InputError
        Two consecutive waypoints are not connected.
    """
    waypoints = np.asarray(waypoints, float)
    parts = []
    for a in range(waypoints.shape[0] - 1):
        try:
            seg = shortest_path(rm, waypoints[a], waypoints[a + 1])
        except InputError:
            na = names[a] if names else f"({waypoints[a][0]:g}, {waypoints[a][1]:g}) px"
            nb = names[a + 1] if names else f"({waypoints[a + 1][0]:g}, {waypoints[a + 1][1]:g}) px"
            raise InputError(
                None, f"{na} and {nb} are not connected through the free space"
            ) from None
        parts.append(seg if a == 0 else seg[1:])
    return np.vstack(parts)


def random_start_goal(
    rm: Roadmap, rng: np.random.Generator, min_separation: float = 0.3
) -> tuple[np.ndarray, np.ndarray]:
    """Two random roadmap nodes of its largest connected part, at least ``min_separation``
    of that part's extent apart when possible. Returns plan pixels ``(x, y)``.

    Parameters
    ----------
    rm : Roadmap
        From :func:`build_roadmap`.
    rng : numpy.random.Generator
        Source of the draw.
    min_separation : float
        Wanted distance as a fraction of the largest part's extent.

    Returns
    -------
    start, goal : (2,) float arrays
        Plan pixels.
    """
    _, labels = connected_components(rm.graph, directed=False)
    biggest = np.flatnonzero(labels == np.bincount(labels).argmax())
    pts = rm.nodes[biggest]
    extent = float(np.hypot(*(pts.max(0) - pts.min(0))))
    best = None
    for _ in range(50):
        a, b = rng.choice(biggest, 2, replace=biggest.size < 2)
        d = float(np.hypot(*(rm.nodes[a] - rm.nodes[b])))
        if best is None or d > best[0]:
            best = (d, a, b)
        if d >= min_separation * extent:
            break
    _, a, b = best
    return rm.nodes[a].copy(), rm.nodes[b].copy()


def random_tour(rm: Roadmap, rng: np.random.Generator, n: int = 4) -> np.ndarray:
    """``n`` roadmap nodes of its largest connected part spread over it (greedy farthest
    point sampling from a random first node): waypoints of a tour that explores the plan.
    Returns (n, 2) plan pixels.

    Parameters
    ----------
    rm : Roadmap
        From :func:`build_roadmap`.
    rng : numpy.random.Generator
        Picks the first node.
    n : int
        Number of waypoints.

    Returns
    -------
    (n, 2) float array
        Plan pixels, in visiting order.

    Examples
    --------
    >>> data = np.zeros((60, 100), np.uint8); data[5:55, 5:95] = 255
    >>> from map2map.core.grid import OccupancyMap
    >>> rm = build_roadmap(OccupancyMap(data, 0.05), rng=np.random.default_rng(0))
    >>> random_tour(rm, np.random.default_rng(1), 3).shape
    (3, 2)
    """
    _, labels = connected_components(rm.graph, directed=False)
    biggest = np.flatnonzero(labels == np.bincount(labels).argmax())
    pts = rm.nodes[biggest]
    chosen = [int(rng.integers(biggest.size))]
    dist = np.hypot(*(pts - pts[chosen[0]]).T)
    for _ in range(1, min(n, biggest.size)):
        nxt = int(np.argmax(dist))
        chosen.append(nxt)
        dist = np.minimum(dist, np.hypot(*(pts - pts[nxt]).T))
    return pts[chosen].copy()
