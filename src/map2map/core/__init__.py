"""The bottom layer: what every other package of map2map builds on.

* :mod:`~map2map.core.grid` -- the one internal map convention (:class:`OccupancyMap`,
  occupied 0, free 255, unknown 127, metres per pixel, ROS origin);
* :mod:`~map2map.core.errors` -- :class:`InputError`, the one-line bad-input error;
* :mod:`~map2map.core._io` -- atomic file writing (temporary name, then rename);
* :mod:`~map2map.core.viz` -- figure helpers (matplotlib, loaded on first use);
* :mod:`~map2map.core.parallel` -- per-item work on the cores in worker processes
  (joblib's loky pool, loaded on first use).

Nothing here imports another map2map package. This module imports none of its
submodules, so ``import map2map.core`` costs nothing.
"""
