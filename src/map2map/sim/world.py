"""The simulated world: the plan, optional furniture, and people walking around.

Furniture (static boxes) is added to the plan before driving and people (discs)
walk between random goals; the lidar sees both, but neither is in the plan, so a
map built from the scans differs from the plan exactly as a real one would.
Furniture never disconnects the free space: a box that would cut off part of the
robot's reachable space (keeping passages of about 0.7 m, :data:`FURNITURE_PASSAGE`),
or cover the start, is redrawn.

The robot may only be where the plan is *free*: walls, furniture, unknown cells
and the outside all block it. :meth:`World.clearance_at` gives the distance from
a point to the nearest blocking cell.

Examples
--------
>>> import numpy as np
>>> from map2map.core.grid import OccupancyMap
>>> data = np.full((80, 80), 255, np.uint8); data[[0, -1], :] = 0; data[:, [0, -1]] = 0
>>> w = World.build(OccupancyMap(data, 0.05), start=(2.0, 2.0, 0.0), obstacles=3, people=1,
...                 rng=np.random.default_rng(1))
>>> len(w.furniture), w.people.positions.shape
(3, (1, 2))
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from ..core.errors import InputError
from ..core.grid import OccupancyMap
from .lidar import Scene

__all__ = ["World", "People", "FURNITURE_PASSAGE"]

#: Furniture must leave every region reachable with this much clearance beyond the
#: robot radius (passages at least about 0.7 m wide), as a furnished home does.
FURNITURE_PASSAGE = 0.15


@dataclass
class People:
    """People as discs walking at constant speed towards random goals."""

    positions: np.ndarray  # (K, 2)
    goals: np.ndarray  # (K, 2)
    radius: float = 0.2
    speed: float = 0.6
    wait: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def circles(self) -> np.ndarray:
        k = len(self.positions)
        return np.column_stack([self.positions, np.full(k, self.radius)]) if k else np.zeros((0, 3))


class World:
    """Plan + furniture + people, with the grids the simulator needs.

    Use :meth:`World.build`. Attributes: ``plan`` (the input plan), ``solid``
    (cells that stop laser beams), ``blocked`` (cells the robot body may not
    touch), ``furniture`` (list of ``(row0, row1, col0, col1)`` boxes),
    ``people``, ``scene`` (for the lidar).
    """

    def __init__(self, plan: OccupancyMap, blocked: np.ndarray, solid: np.ndarray, furniture):
        self.plan = plan
        self.blocked = blocked
        self.solid = solid
        self.furniture = furniture
        self.scene = Scene(plan, solid)
        # distance (m) from each cell centre to the nearest blocked cell centre,
        # minus half a cell: a conservative distance to the blocked squares
        self.clearance = _clearance(blocked, plan.resolution)
        self.people = People(np.zeros((0, 2)), np.zeros((0, 2)))

    # ------------------------------------------------------------ geometry
    def clearance_at(self, xs, ys) -> np.ndarray:
        """Distance (m) from points (plan frame) to the nearest blocked cell; 0 outside.

        Parameters
        ----------
        xs, ys : array-like
            Points, metres.

        Returns
        -------
        ndarray of float
        """
        r, c = self.plan.world_to_pixel(xs, ys)
        inside = self.plan.contains(r, c)
        out = np.zeros(np.shape(r))
        out[inside] = self.clearance[r[inside], c[inside]]
        return out

    def reachable_cells(self, start, radius: float, margin: float = 0.0) -> np.ndarray:
        """Cells the robot's body can cover: the start's component of centres with at
        least ``radius + margin`` clearance, dilated by ``radius``.

        With a ``margin`` (the clearance a navigation stack keeps, e.g. 5 cm) gaps the
        robot could only squeeze through touching both sides do not count as reachable.

        Parameters
        ----------
        start : (x, y, theta)
            Start pose.
        radius : float
            Robot radius, metres.
        margin : float
            Extra clearance, metres.

        Returns
        -------
        (H, W) bool array
        """
        ok = self.clearance >= radius + margin
        r, c = (int(v) for v in self.plan.world_to_pixel(start[0], start[1]))
        if not ok[r, c]:  # a start closer to a wall than the margin: use its own region
            ok = self.clearance >= radius
        rad = radius / self.plan.resolution
        k = int(math.ceil(rad))
        out = np.zeros(ok.shape, bool)
        box = _bbox(ok, k) if ok[r, c] else None  # the cells that can take part, k wider
        r0, r1, c0, c1 = box or (0, ok.shape[0], 0, ok.shape[1])
        lab, _ = ndimage.label(ok[r0:r1, c0:c1])
        comp = lab == lab[r - r0, c - c0]
        out[r0:r1, c0:c1] = _dilate_disk(comp, rad) & ~self.blocked[r0:r1, c0:c1]
        return out

    # ------------------------------------------------------------ building
    @classmethod
    def build(
        cls,
        plan: OccupancyMap,
        *,
        start,
        obstacles: int = 0,
        people: int = 0,
        robot_radius: float = 0.2,
        rng: np.random.Generator,
    ) -> World:
        """The world for a run: ``obstacles`` furniture boxes and ``people`` walkers (seeded).

        Parameters
        ----------
        plan : OccupancyMap
            The plan.
        start : (x, y, theta)
            Robot start (kept clear of furniture and people).
        obstacles, people : int
            Counts.
        robot_radius : float
            Metres.
        rng : numpy.random.Generator
            Source of the placements.

        Returns
        -------
        World
        """
        blocked = ~plan.free
        solid = plan.occupied.copy()
        world = cls(plan, blocked, solid, [])
        if obstacles > 0:
            world._add_furniture(int(obstacles), start, robot_radius, rng)
        if people > 0:
            world._add_people(int(people), start, rng)
        return world

    def _add_furniture(self, n, start, robot_radius, rng):
        res = self.plan.resolution
        margins = (0.05, FURNITURE_PASSAGE)
        reach = [self.reachable_cells(start, robot_radius, mg) for mg in margins]
        sr, sc = (int(v) for v in self.plan.world_to_pixel(start[0], start[1]))
        keep_out = int(math.ceil((robot_radius + 0.3) / res))
        # a box may take away reachable space only right around itself
        near = int(math.ceil((2 * robot_radius + FURNITURE_PASSAGE) / res)) + 1
        free_r, free_c = np.nonzero(self.clearance >= 0.0)
        if len(free_r) == 0:
            return
        blocked, solid = self.blocked.copy(), self.solid.copy()
        placed, tries = [], 0
        while len(placed) < n and tries < 40 * n:
            tries += 1
            h = int(round(rng.uniform(0.3, 1.2) / res))
            w = int(round(rng.uniform(0.3, 1.2) / res))
            i = int(rng.integers(len(free_r)))
            r0, c0 = int(free_r[i]) - h // 2, int(free_c[i]) - w // 2
            r0 = max(0, min(r0, self.plan.height - h))
            c0 = max(0, min(c0, self.plan.width - w))
            box = (r0, r0 + h, c0, c0 + w)
            if (
                box[0] - keep_out <= sr < box[1] + keep_out
                and box[2] - keep_out <= sc < box[3] + keep_out
            ):
                continue
            if self.blocked[box[0] : box[1], box[2] : box[3]].mean() > 0.5:
                continue  # mostly inside walls or outside
            trial_b, trial_s = blocked.copy(), solid.copy()
            trial_b[box[0] : box[1], box[2] : box[3]] = True
            trial_s[box[0] : box[1], box[2] : box[3]] = True
            trial = World(self.plan, trial_b, trial_s, [])
            around = np.zeros_like(trial_b)
            around[max(0, box[0] - near) : box[1] + near, max(0, box[2] - near) : box[3] + near] = (
                True
            )
            after = [trial.reachable_cells(start, robot_radius, mg) for mg in margins]
            if any((b & ~a & ~around).any() for b, a in zip(reach, after, strict=True)):
                continue  # it would cut off (or squeeze shut) space beyond it
            blocked, solid = trial_b, trial_s
            reach = after
            placed.append(box)
        self.__init__(self.plan, blocked, solid, placed)

    def _add_people(self, n, start, rng):
        ok_r, ok_c = np.nonzero(self.clearance >= 0.4)
        if len(ok_r) == 0:
            return
        xs, ys = self.plan.pixel_to_world(ok_r, ok_c)
        far = np.hypot(xs - start[0], ys - start[1]) > 1.0
        if far.any():
            xs, ys = xs[far], ys[far]
        idx = rng.integers(len(xs), size=n)
        gidx = rng.integers(len(xs), size=n)
        self._goal_pool = np.column_stack([xs, ys])
        self.people = People(
            np.column_stack([xs[idx], ys[idx]]),
            np.column_stack([xs[gidx], ys[gidx]]),
            wait=np.zeros(n),
        )
        self.scene.circles = self.people.circles

    def step_people(self, dt: float, robot_xy, rng: np.random.Generator) -> None:
        """Walk every person towards their goal; new goal when reached or stuck.

        Parameters
        ----------
        dt : float
            Seconds.
        robot_xy : (x, y)
            Robot position (people keep away from it).
        rng : numpy.random.Generator
            Source of new goals.
        """
        pp = self.people
        if len(pp.positions) == 0:
            return
        for k in range(len(pp.positions)):
            if pp.wait[k] > 0:
                pp.wait[k] -= dt
                continue
            d = pp.goals[k] - pp.positions[k]
            dist = float(np.hypot(*d))
            if dist < 0.1:
                pp.goals[k] = self._goal_pool[rng.integers(len(self._goal_pool))]
                pp.wait[k] = rng.uniform(0.0, 3.0)
                continue
            new = pp.positions[k] + d / dist * min(pp.speed * dt, dist)
            clear = self.clearance_at(new[0:1], new[1:2])[0] >= pp.radius
            d_new = math.hypot(new[0] - robot_xy[0], new[1] - robot_xy[1])
            d_old = math.hypot(pp.positions[k][0] - robot_xy[0], pp.positions[k][1] - robot_xy[1])
            near_robot = d_new < 0.6 and d_new <= d_old  # stepping away is always fine
            if clear and not near_robot:
                pp.positions[k] = new
            else:  # blocked: pick another goal after a short pause
                pp.goals[k] = self._goal_pool[rng.integers(len(self._goal_pool))]
                pp.wait[k] = rng.uniform(0.5, 2.0)
        self.scene.circles = pp.circles


def _bbox(mask: np.ndarray, pad: int) -> tuple[int, int, int, int] | None:
    """Half-open ``(r0, r1, c0, c1)`` of the true cells of ``mask``, ``pad`` cells wider
    (clipped to the grid); None if there are none."""
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(mask.any(axis=0))
    h, w = mask.shape
    return (max(int(rows[0]) - pad, 0), min(int(rows[-1]) + 1 + pad, h),
            max(int(cols[0]) - pad, 0), min(int(cols[-1]) + 1 + pad, w))  # fmt: skip


def _clearance(blocked: np.ndarray, resolution: float) -> np.ndarray:
    """``(distance_transform_edt(~blocked) - 0.5) * resolution``, the distance computed
    over the unblocked cells' bounding box plus one cell only: every cell outside it is
    blocked (distance 0), and the blocked ring around the box is nearer to a cell inside
    than anything beyond it, so the values are the same as over the whole grid (a
    HouseExpo render is a 12 MP picture of which the building is a tenth)."""
    out = np.full(blocked.shape, (0.0 - 0.5) * resolution)
    box = _bbox(~blocked, 1)
    if box is not None:
        r0, r1, c0, c1 = box
        edt = ndimage.distance_transform_edt(~blocked[r0:r1, c0:c1])
        out[r0:r1, c0:c1] = (edt - 0.5) * resolution
    return out


def _dilate_disk(mask: np.ndarray, rad: float) -> np.ndarray:
    """``binary_dilation(mask, disk)`` with the disk ``x**2 + y**2 <= rad**2`` (pixels),
    from the exact nearest true cell of the feature transform: the same cells, without
    the cost of a structure of ``(2 rad + 1)**2`` elements (1 s per MP at 1 cm/px)."""
    if not mask.any():
        return mask.copy()
    idx = ndimage.distance_transform_edt(~mask, return_distances=False, return_indices=True)
    rr, cc = np.indices(mask.shape)
    d2 = (idx[0] - rr) ** 2 + (idx[1] - cc) ** 2
    return d2 <= rad**2


def check_start(world: World, start, radius: float, source) -> None:
    """Raise InputError if the robot cannot stand at ``start``.

    Parameters
    ----------
    world : World
        The plan with its clearance.
    start : (x, y, theta)
        Start pose, plan frame.
    radius : float
        Robot radius, metres.
    source : path-like or str
        Named in errors.

    Raises
    ------
    InputError
        Outside the plan, or too close to a wall.
    """
    x, y = float(start[0]), float(start[1])
    r, c = world.plan.world_to_pixel(x, y)
    if not world.plan.contains(r, c):
        raise InputError(source, f"start pose ({x:.2f}, {y:.2f}) is outside the plan")
    if world.clearance_at([x], [y])[0] < radius:
        raise InputError(
            source,
            f"start pose ({x:.2f}, {y:.2f}) is in or too close to a wall "
            f"(the robot needs {radius:.2f} m of clearance)",
        )
