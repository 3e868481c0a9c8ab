"""A learned generative model of a particle filter's pose error (issue #33: the SLAM error
of a synthesized map drawn by a network trained on simulated runs, not by hand).

A SLAM run's map is its scans counted into a grid at the poses its filter estimated
(:mod:`map2map.learn.ab.scans`). The estimate errs in a way set by how the robot moves and
what it sees: the error walks while the robot maps new ground (faster in a corridor, where
the scans fix nothing along it, and when it turns), comes back to the map's own error where
the robot sees again what it mapped before (the filter localises against its map: a room
revisited is not saved twice unless the error has moved on), and jitters from scan to scan.
The hand-made drawn pose error (room-wise drift, a turn, a correlated jitter;
``pose_error="drawn"``) is told apart from simulated runs: its walls bend and are saved
twice too often (docs/synthesize.md). This model learns the error process instead, from the
``rbpf`` filter's own trajectories on generated plans:

the error of node ``i`` (a scan the filter processed), ``e_i = F_i - P_i`` (its estimated
minus its true pose, plan frame; the map is anchored at the start, so ``e_0 = 0``), steps by
``d_i = e_i - e_{i-1}``, and ``d_i`` in the robot's frame is drawn from a mixture of
``COMPONENTS`` Gaussians whose weights, means and covariances (a Cholesky factor: a
heading step and a sideways step come together, as a scan matcher turns and shifts a pose
at once) an MLP computes from (:func:`step_features`):

- the robot's motion since the previous node (forward, sideways, turn) and the seconds;
- the error so far (in the robot's frame), its distance from its own moving averages over
  ``EMA_S`` seconds, and what a heading error does to the motion (a step ``u`` taken with
  heading error ``e_theta`` moves the estimate by about ``e_theta x u``);
- the previous two steps of the error (the jitter's memory);
- the map's own error where the robot looks (:class:`ErrorMemory`: the errors of the
  nodes more than ``MEMORY_S`` seconds old whose view centre lies near this one's, by
  weight), the same of the recent map (``RECENT_S`` to ``MEMORY_S`` seconds old), and how
  much of each is there;
- what the scan constrains (:func:`scan_geometry`: the scan's surface normals' second
  moment in the robot frame: a corridor constrains only across it).

Sampling runs the same step function along a recorded exploration's true poses
(:meth:`PoseErrorModel.sample`), each step drawn from the model with the error drawn so far;
training (:func:`training_pairs`; :mod:`map2map.learn.ab.pose_error_train`) runs it along
the filter's own errors (teacher forcing), so the features are computed by one function in
both.

Examples
--------
>>> P = np.array([[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0.6, 0.0, 0.1]])
>>> E = np.array([[0.0, 0.0, 0.0], [0.01, 0.0, 0.002], [0.02, 0.005, 0.004]])
>>> geo = np.zeros((3, GEOMETRY))
>>> X, Y = training_pairs(P, E, np.array([0.0, 0.5, 1.0]), geo)
>>> X.shape == (2, FEATURES), Y.shape
(True, (2, 3))
>>> np.round(Y[0], 3).tolist()       # the first step in the robot's frame: cm, cm, deg
[1.0, 0.0, 0.115]
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...core.errors import InputError
from ...core.geometry import wrap_angle

__all__ = ["FEATURES", "GEOMETRY", "COMPONENTS", "MEMORY_S", "MEMORY_M", "scan_geometry",
           "ErrorMemory", "step_features", "training_pairs", "PoseErrorModel",
           "load_pose_error", "PRETRAINED", "errors_along"]

#: Seconds after which a node's scan counts as the map (the filter localises against it).
MEMORY_S = 15.0
#: Seconds after which a node counts as the recent map (the scans just before the step are
#: the steps' own history, not the map).
RECENT_S = 2.0
#: Radius (metres, Gaussian) around a node's view centre within which the map's error counts.
MEMORY_M = 0.75
#: How far ahead of the robot its view centre lies (metres; the LIDAR looks ahead, 180 deg).
VIEW_M = 1.0
#: The scans' usable range for :func:`scan_geometry` (GMapping's ``maxUrange``).
GEOMETRY_RANGE = 3.0
#: Columns of :func:`scan_geometry`.
GEOMETRY = 4
#: Columns of :func:`step_features`.
FEATURES = 41
#: Outputs of the MLP per mixture component: weight logit, mean (3), log of the Cholesky
#: factor's diagonal (3) and its lower off-diagonal (3).
PER_COMPONENT = 10
#: Time constants (seconds) of the error's moving averages the steps revert to.
EMA_S = (2.0, 10.0)
#: Mixture components of a step.
COMPONENTS = 2
#: The shipped weights' file name (``map2map/learn/ab/weights``).
PRETRAINED = "pose_error.safetensors"

_CM = 100.0                         # metres -> the model's centimetres
_DEG = 180.0 / math.pi              # radians -> the model's degrees


def scan_geometry(ranges: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """What each scan constrains: ``(N, GEOMETRY)`` = the second moment of its surface
    normals in the robot's frame (``nxx``, ``nyy``, ``nxy``, each over the beams) and the
    share of beams that hit within ``GEOMETRY_RANGE``.

    ``ranges``, ``angles``: ``(N, B)`` in the laser's frame (no return ``inf``, invalid
    ``nan``, as :func:`~map2map.slam.rbpf.prepare_scan`). A normal is the perpendicular of
    the segment between two neighbouring hits less than 0.15 m apart. A corridor along x
    gives ``nyy`` >> ``nxx``.

    Examples
    --------
    >>> a = np.linspace(-np.pi / 2, np.pi / 2, 181)[None]
    >>> wall = 1.0 / np.cos(a)                       # a wall 1 m ahead, across the robot
    >>> wall[np.abs(wall) > 3] = np.inf
    >>> g = scan_geometry(wall, a)
    >>> bool(g[0, 0] > 0.3 and g[0, 1] < 1e-6 and abs(g[0, 2]) < 1e-6)
    True
    """
    r = np.asarray(ranges, float)
    a = np.asarray(angles, float)
    if r.ndim == 1:
        r, a = r[None], a[None]
    ok = np.isfinite(r) & (r <= GEOMETRY_RANGE)
    r0 = np.where(ok, r, np.nan)
    x, y = r0 * np.cos(a), r0 * np.sin(a)
    tx, ty = np.diff(x, axis=1), np.diff(y, axis=1)
    n = np.hypot(tx, ty)
    good = np.isfinite(n) & (n < 0.15) & (n > 1e-9)
    nx = np.where(good, -ty / np.where(good, n, 1.0), 0.0)
    ny = np.where(good, tx / np.where(good, n, 1.0), 0.0)
    b = max(r.shape[1], 1)
    return np.stack([(nx * nx).sum(1) / b, (ny * ny).sum(1) / b, (nx * ny).sum(1) / b,
                     ok.sum(1) / b], axis=1)


def _view(P: np.ndarray) -> np.ndarray:
    """View centres ``(N, 2)`` of poses ``(N, 3)``: ``VIEW_M`` ahead."""
    P = np.asarray(P, float).reshape(-1, 3)
    return P[:, :2] + VIEW_M * np.stack([np.cos(P[:, 2]), np.sin(P[:, 2])], axis=1)


class ErrorMemory:
    """The map's error where the robot looks: the nodes' view centres, times and errors so
    far, queried as the weighted mean error of the nodes at least ``MEMORY_S`` seconds old
    (weights ``exp(-d^2 / 2 MEMORY_M^2)`` of the distance between view centres).

    Examples
    --------
    >>> m = ErrorMemory(4)
    >>> m.add((0.0, 0.0, 0.0), 0.0, (0.1, 0.0, 0.01))
    >>> m.query((0.0, 0.0, 0.0), 5.0)[1]           # too recent: no map yet
    0.0
    >>> e, w = m.query((0.0, 0.0, 0.0), 20.0)
    >>> np.round(e, 2).tolist(), round(w, 2)
    ([0.1, 0.0, 0.01], 1.0)
    """

    def __init__(self, n: int):
        self.view = np.zeros((n, 2))
        self.t = np.zeros(n)
        self.e = np.zeros((n, 3))
        self.n = 0

    def add(self, pose, t: float, e) -> None:
        """Store a node (true ``pose``, seconds ``t``, its error ``e``)."""
        self.view[self.n] = _view(np.asarray(pose, float))[0]
        self.t[self.n] = t
        self.e[self.n] = e
        self.n += 1

    def query(self, pose, t: float, older: float = MEMORY_S,
              newer: float | None = None) -> tuple[np.ndarray, float]:
        """``(mean error, total weight)`` of the map at ``pose``'s view at time ``t``: of
        the nodes at least ``older`` seconds old (and, with ``newer``, less than ``newer``
        seconds old)."""
        k = int(np.searchsorted(self.t[:self.n], float(t) - older, side="right"))
        j = 0 if newer is None else \
            int(np.searchsorted(self.t[:self.n], float(t) - newer, side="right"))
        if k <= j:
            return np.zeros(3), 0.0
        d2 = ((self.view[j:k] - _view(np.asarray(pose, float))[0]) ** 2).sum(1)
        w = np.exp(-d2 / (2 * MEMORY_M * MEMORY_M))
        s = float(w.sum())
        if s < 1e-9:
            return np.zeros(3), 0.0
        return (w[:, None] * self.e[j:k]).sum(0) / s, s

    def both(self, pose, t: float) -> tuple[tuple, tuple]:
        """The map's error (:meth:`query`) and the recent map's (``RECENT_S`` to
        ``MEMORY_S`` seconds old)."""
        return self.query(pose, t), self.query(pose, t, RECENT_S, MEMORY_S)


def _to_robot(v, th: float) -> tuple[float, float]:
    c, s = math.cos(th), math.sin(th)
    return c * v[0] + s * v[1], -s * v[0] + c * v[1]


class _Averages:
    """Exponential moving averages of the error with the time constants ``EMA_S``."""

    def __init__(self):
        self.v = np.zeros((len(EMA_S), 3))

    def update(self, e, dt: float) -> None:
        for j, tau in enumerate(EMA_S):
            a = math.exp(-max(float(dt), 0.0) / tau)
            self.v[j] = a * self.v[j] + (1.0 - a) * np.asarray(e, float)


def _memory_features(memory: tuple, e_prev, th: float) -> list[float]:
    """A memory's pull: its error minus ``e_prev`` (robot frame, cm / 10 and degrees),
    the same gated by its weight ``w / (1 + w)``, the gate and ``log(1 + w)``."""
    m, w = memory
    if w > 0:
        mx, my = _to_robot((m[0] - e_prev[0], m[1] - e_prev[1]), th)
        mth = float(m[2] - e_prev[2])
    else:
        mx = my = mth = 0.0
    gate = w / (1.0 + w)
    return [mx * _CM / 10, my * _CM / 10, mth * _DEG,
            gate * mx * _CM, gate * my * _CM, gate * mth * _DEG, gate, math.log1p(w)]


def step_features(p_prev, p, dt: float, e_prev, d1, d2, memory: tuple, geo,
                  averages=None) -> np.ndarray:
    """The MLP's input for the step to node ``p`` (module doc): ``(FEATURES,)``.

    ``p_prev``, ``p``: true poses (plan frame); ``e_prev``: the error at the previous node,
    ``d1``, ``d2``: the previous two steps (metres, radians, plan frame); ``memory``:
    :meth:`ErrorMemory.both` (the map's error and the recent map's); ``geo``: the node's
    :func:`scan_geometry` row; ``averages``: ``(len(EMA_S), 3)`` moving averages of the
    error up to ``e_prev`` (None: ``e_prev`` itself).
    """
    th = float(p[2])
    dx, dy = float(p[0] - p_prev[0]), float(p[1] - p_prev[1])
    fwd, lat = _to_robot((dx, dy), th)
    turn = math.remainder(float(p[2] - p_prev[2]), math.tau)
    ex, ey = _to_robot(e_prev, th)
    eth = float(e_prev[2])
    a1 = _to_robot(d1, th)
    a2 = _to_robot(d2, th)
    av = np.tile(np.asarray(e_prev, float), (len(EMA_S), 1)) if averages is None \
        else np.asarray(averages, float)
    dev = []
    for j in range(len(EMA_S)):
        a = _to_robot((e_prev[0] - av[j, 0], e_prev[1] - av[j, 1]), th)
        dev += [a[0] * _CM, a[1] * _CM, float(e_prev[2] - av[j, 2]) * _DEG]
    return np.array([
        fwd / 0.3, lat / 0.05, turn / 0.2, dt,
        ex * _CM / 10, ey * _CM / 10, eth * _DEG,
        -eth * lat * _CM, eth * fwd * _CM,
        a1[0] * _CM, a1[1] * _CM, float(d1[2]) * _DEG,
        a2[0] * _CM, a2[1] * _CM, float(d2[2]) * _DEG,
        *dev,
        *_memory_features(memory[0], e_prev, th),
        *_memory_features(memory[1], e_prev, th),
        *(np.asarray(geo, float) * np.array([4.0, 4.0, 4.0, 1.0])),
    ])


def _step_target(d, th: float) -> np.ndarray:
    """A step ``d`` (plan frame, metres/radians) in the robot's frame, cm and degrees."""
    x, y = _to_robot(d, th)
    return np.array([x * _CM, y * _CM, float(d[2]) * _DEG])


def _wrap(e: np.ndarray) -> np.ndarray:
    """Errors ``(.., 3)`` with their heading wrapped (:func:`~map2map.core.geometry.wrap_angle`)."""
    e = np.array(e, float, copy=True)
    e[..., 2] = wrap_angle(e[..., 2])
    return e


def training_pairs(P: np.ndarray, E: np.ndarray, t: np.ndarray,
                   geo: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(X, Y)`` of one recorded run: the features of each step (:func:`step_features`,
    along the recorded errors ``E`` = filter minus true poses at the nodes ``P``, times
    ``t``) and the step taken (robot frame, cm and degrees)."""
    P = np.asarray(P, float)
    E = _wrap(np.asarray(E, float))
    n = len(P)
    X = np.zeros((max(n - 1, 0), FEATURES))
    Y = np.zeros((max(n - 1, 0), 3))
    mem = ErrorMemory(n)
    mem.add(P[0], t[0], E[0])
    avg = _Averages()
    d1 = d2 = np.zeros(3)
    for i in range(1, n):
        dt = float(t[i] - t[i - 1])
        X[i - 1] = step_features(P[i - 1], P[i], dt, E[i - 1], d1, d2,
                                 mem.both(P[i], t[i]), geo[i], avg.v)
        d = E[i] - E[i - 1]
        Y[i - 1] = _step_target(d, float(P[i, 2]))
        d2, d1 = d1, d
        mem.add(P[i], t[i], E[i])
        avg.update(E[i], dt)
    return X, Y


def _mixture(o, xp):
    """The mixture of the MLP's outputs ``o`` (.., COMPONENTS * PER_COMPONENT): log
    weights, means and lower-triangular Cholesky factors, for numpy or torch (``xp``)."""
    k = COMPONENTS
    if xp is np:
        logw = o[..., :k] - np.logaddexp.reduce(o[..., :k], axis=-1, keepdims=True)
        ld = np.clip(o[..., 4 * k:7 * k], -7.0, 4.0)
        L = np.zeros((*o.shape[:-1], k, 3, 3))
    else:
        logw = xp.log_softmax(o[..., :k], dim=-1)
        ld = o[..., 4 * k:7 * k].clamp(-7.0, 4.0)
        L = xp.zeros((*o.shape[:-1], k, 3, 3), dtype=o.dtype)
    mu = o[..., k:4 * k].reshape(*o.shape[:-1], k, 3)
    ld = ld.reshape(*o.shape[:-1], k, 3)
    off = o[..., 7 * k:10 * k].reshape(*o.shape[:-1], k, 3)
    diag = xp.exp(ld)
    L[..., 0, 0], L[..., 1, 1], L[..., 2, 2] = diag[..., 0], diag[..., 1], diag[..., 2]
    L[..., 1, 0], L[..., 2, 0], L[..., 2, 1] = off[..., 0], off[..., 1], off[..., 2]
    return logw, mu, L


@dataclass
class PoseErrorModel:
    """The trained model: an MLP (``weights``: ``w0, b0, w1, b1, w2, b2``, numpy) from
    :func:`step_features` (standardised by ``mean``/``std``) to a step's mixture
    (``COMPONENTS`` weights, means and lower-triangular Cholesky factors of three
    coordinates), and ``config`` (how it was trained)."""

    weights: dict
    mean: np.ndarray
    std: np.ndarray
    config: dict

    def mixture(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(log weights (.., K), means (.., K, 3), Cholesky factors (.., K, 3, 3))`` of
        features ``x`` (.., FEATURES)."""
        h = (np.asarray(x, float) - self.mean) / self.std
        w = self.weights
        h = h @ w["w0"] + w["b0"]
        h = h / (1.0 + np.exp(-h))
        h = h @ w["w1"] + w["b1"]
        h = h / (1.0 + np.exp(-h))
        o = h @ w["w2"] + w["b2"]
        return _mixture(o, np)

    def log_likelihood(self, X: np.ndarray, Y: np.ndarray) -> float:
        """Mean log-likelihood per step of steps ``Y`` given features ``X``."""
        logw, mu, L = self.mixture(X)
        r = np.asarray(Y, float)[..., None, :] - mu
        z = np.linalg.solve(L, r[..., None])[..., 0]
        diag = np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(-1)
        lp = -0.5 * (z * z).sum(-1) - diag - 1.5 * math.log(2 * math.pi) + logw
        return float(np.logaddexp.reduce(lp, axis=-1).mean())

    def sample(self, P: np.ndarray, t: np.ndarray, geo: np.ndarray,
               rng: np.random.Generator) -> np.ndarray:
        """Errors ``(N, 3)`` (metres, radians, plan frame) drawn along the true poses ``P``
        of a run's nodes (times ``t``, scans' :func:`scan_geometry` ``geo``), one step at
        a time from ``rng``; ``e_0 = 0``. A step is kept within ``config["step_max"]``
        (robot frame, cm and degrees) and the error within ``config["error_max"]``
        (metres, metres, radians): twice the largest the training runs took.
        """
        P = np.asarray(P, float)
        n = len(P)
        E = np.zeros((n, 3))
        if n == 0:
            return E
        # never beyond what training saw (a model asked outside its runs: no runaway)
        step_max = np.asarray(self.config.get("step_max", [np.inf] * 3), float)
        error_max = np.asarray(self.config.get("error_max", [np.inf] * 3), float)
        mem = ErrorMemory(n)
        mem.add(P[0], t[0], E[0])
        avg = _Averages()
        d1 = d2 = np.zeros(3)
        u = rng.random(n)
        z = rng.standard_normal((n, 3))
        for i in range(1, n):
            dt = float(t[i] - t[i - 1])
            x = step_features(P[i - 1], P[i], dt, E[i - 1], d1, d2, mem.both(P[i], t[i]),
                              geo[i], avg.v)
            logw, mu, L = self.mixture(x)
            k = min(int(np.searchsorted(np.cumsum(np.exp(logw)), u[i])), COMPONENTS - 1)
            s = np.clip(mu[k] + L[k] @ z[i], -step_max, step_max)
            th = float(P[i, 2])
            c, sn = math.cos(th), math.sin(th)
            d = np.array([(c * s[0] - sn * s[1]) / _CM, (sn * s[0] + c * s[1]) / _CM,
                          s[2] / _DEG])
            E[i] = np.clip(E[i - 1] + d, -error_max, error_max)
            d = E[i] - E[i - 1]
            d2, d1 = d1, d
            mem.add(P[i], t[i], E[i])
            avg.update(E[i], dt)
        return E

    def save(self, path: str | os.PathLike) -> None:
        """Write safetensors with the config in its header, and ``.json`` beside it,
        atomically."""
        from safetensors.numpy import save_file

        from ...core._io import atomic_paths

        path = Path(path)
        tensors = {k: np.ascontiguousarray(v, np.float32) for k, v in self.weights.items()}
        tensors["mean"] = np.asarray(self.mean, np.float32)
        tensors["std"] = np.asarray(self.std, np.float32)
        header = {"config": json.dumps(self.config, sort_keys=True)}
        with atomic_paths(path, path.with_suffix(".json")) as (tmp, tmpj):
            save_file(tensors, str(tmp), metadata=header)
            tmpj.write_text(json.dumps(self.config, indent=1, sort_keys=True) + "\n")


def load_pose_error(path: str | os.PathLike | None = None) -> PoseErrorModel:
    """The model in ``path`` (safetensors of :meth:`PoseErrorModel.save`; None: the shipped
    weights).

    Raises
    ------
    InputError
        The file is missing or not such a model.
    """
    if path is None:
        path = Path(__file__).parent / "weights" / PRETRAINED
    path = Path(path)
    if not path.is_file():
        raise InputError(str(path), "no pose-error model there")
    try:
        from safetensors import safe_open
    except ImportError as exc:            # pragma: no cover - the learn extra
        raise InputError(str(path), "the learned pose error needs safetensors: "
                         "pip install 'map2map[learn]'") from exc
    try:
        with safe_open(str(path), framework="numpy") as f:
            meta = f.metadata() or {}
            t = {k: f.get_tensor(k).astype(float) for k in f.keys()}
        config = json.loads(meta.get("config", "{}"))
        w = {k: t[k] for k in ("w0", "b0", "w1", "b1", "w2", "b2")}
        return PoseErrorModel(w, t["mean"], t["std"], config)
    except Exception as exc:              # safetensors' own errors, a missing tensor
        raise InputError(str(path), f"not a pose-error model ({exc})") from exc


_LOADED: dict = {}


def errors_along(ex, model: str | os.PathLike | None,
                 rng: np.random.Generator) -> np.ndarray:
    """Pose errors ``(len(ex.keep), 3)`` drawn by the model in ``model`` (None: the shipped
    one; loaded once a process, per file version) along an exploration's true poses at
    the scans its mapper processed (``ex``: a :class:`~map2map.learn.ab.scans.Exploration`
    with ``keep``)."""
    from ...slam.rbpf import prepare_scan

    key = None if model is None else (str(model), os.stat(model).st_mtime_ns) \
        if os.path.isfile(model) else str(model)
    if key not in _LOADED:
        _LOADED[key] = load_pose_error(model)
    keep = np.asarray(ex.keep, int)
    if len(keep) == 0:
        return np.zeros((0, 3))
    ra = [prepare_scan(ex.scans[i]) for i in keep]
    geo = scan_geometry(np.stack([r for r, _ in ra]), np.stack([a for _, a in ra]))
    return _LOADED[key].sample(ex.poses[keep], np.asarray(ex.times, float)[keep], geo, rng)
