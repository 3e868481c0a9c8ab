"""Routes for the simulator to drive instead of exploring: waypoints and recorded trajectories.

File formats (the same as :mod:`map2map.trajectory` of the parametric model):

* **waypoints**: one ``x y`` or ``x,y`` pair (optionally ``x,y,theta``) per line,
  metres in the plan's world frame; ``#`` comments and a header line allowed.
* **trajectory**: CSV rows ``x,y,theta`` or ``t,x,y,theta`` (a header naming the
  columns is optional); the robot follows the path at its own speed, so the times
  are not used. Poses closer than ``min_spacing`` are thinned out.

:func:`as_waypoints` also accepts any in-memory route: an ``(N, 2|3)`` array, a
list of points, or an object with ``x`` and ``y`` arrays (such as
``map2map.trajectory.Trajectory`` or a PRM path).

Examples
--------
>>> import tempfile, pathlib
>>> p = pathlib.Path(tempfile.mkdtemp()) / "route.csv"
>>> _ = p.write_text("t,x,y,theta\\n0,1.0,2.0,0\\n1,1.01,2.0,0\\n2,2.0,2.0,0\\n")
>>> read_route(p, "trajectory").tolist()
[[1.0, 2.0, 0.0], [2.0, 2.0, 0.0]]
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = ["read_route", "as_waypoints"]


def _table(path: Path) -> tuple[list[str] | None, np.ndarray]:
    if not path.is_file():
        raise InputError(path, "route file not found")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(path, f"cannot read route file ({exc})") from None
    header = None
    rows: list[list[float]] = []
    for lineno, line in enumerate(text.splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = [v for v in line.replace(",", " ").split() if v]
        try:
            rows.append([float(v) for v in parts])
        except ValueError:
            if header is None and not rows:
                header = [v.strip().lower() for v in parts]
                continue
            raise InputError(path, f"line {lineno}: not a number in {line[:60]!r}") from None
        if len(rows[-1]) != len(rows[0]):
            n, n0 = len(rows[-1]), len(rows[0])
            raise InputError(path, f"line {lineno}: {n} columns, expected {n0}")
    if not rows:
        raise InputError(path, "route file has no points")
    arr = np.array(rows, float)
    if not np.isfinite(arr).all():
        raise InputError(path, "route file has non-finite numbers")
    return header, arr


def read_route(path: str | os.PathLike, kind: str = "waypoints", min_spacing: float = 0.05):
    """Read a waypoints or trajectory file as an ``(N, 2)`` or ``(N, 3)`` array of points."""
    path = Path(path)
    header, arr = _table(path)
    if kind == "waypoints":
        if arr.shape[1] not in (2, 3):
            raise InputError(path, f"waypoints need 2 (x y) or 3 columns, found {arr.shape[1]}")
        if header is not None and header[:2] != ["x", "y"]:
            raise InputError(path, f"waypoints header must start with x,y; got {header}")
        pts = arr
    elif kind == "trajectory":
        if header is not None:
            if not {"x", "y", "theta"} <= set(header) or len(header) != arr.shape[1]:
                raise InputError(path, f"trajectory header must name x, y, theta; got {header}")
            pts = arr[:, [header.index("x"), header.index("y"), header.index("theta")]]
        elif arr.shape[1] == 3:
            pts = arr
        elif arr.shape[1] == 4:
            pts = arr[:, 1:4]
        else:
            raise InputError(
                path,
                f"trajectory needs 3 (x,y,theta) or 4 (t,x,y,theta) columns, not {arr.shape[1]}",
            )
    else:
        raise ValueError(f"unknown route kind {kind!r}")
    return _thin(pts, min_spacing)


def _thin(pts: np.ndarray, spacing: float) -> np.ndarray:
    keep = [0]
    for i in range(1, len(pts)):
        if np.hypot(*(pts[i, :2] - pts[keep[-1], :2])) >= spacing:
            keep.append(i)
    if keep[-1] != len(pts) - 1 and np.hypot(*(pts[-1, :2] - pts[keep[-1], :2])) > 0:
        keep.append(len(pts) - 1)
    return pts[keep]


def as_waypoints(route) -> np.ndarray:
    """Any route object as an ``(N, 2|3)`` float array (see module docstring)."""
    if hasattr(route, "x") and hasattr(route, "y"):
        cols = [np.asarray(route.x, float), np.asarray(route.y, float)]
        if hasattr(route, "theta"):
            cols.append(np.asarray(route.theta, float))
        return _thin(np.column_stack(cols), 0.05)
    return np.asarray(route, float)
