"""Robot trajectories over a floor plan: probabilistic roadmap and timed motion (thesis 3.2).

* :mod:`map2map.trajectory.prm` - roadmap with robot clearance, shortest paths.
* :mod:`map2map.trajectory.timing` - :class:`Trajectory`, turn-and-drive timing, CSV I/O.
"""

from .prm import Roadmap, build_roadmap, path_through, random_start_goal, shortest_path
from .timing import Trajectory, read_trajectory, read_waypoints, time_waypoints

__all__ = [
    "Roadmap",
    "Trajectory",
    "build_roadmap",
    "path_through",
    "random_start_goal",
    "read_trajectory",
    "read_waypoints",
    "shortest_path",
    "time_waypoints",
]
