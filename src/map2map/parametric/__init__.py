"""Parametric CAD->SLAM model, thesis section 3.2 (Fig. 3.2) and 5.2.

Modules follow the data flow:

* :mod:`~map2map.parametric.params` - every parameter, documented defaults, YAML I/O;
* :mod:`~map2map.parametric.visibility` - pixels the LIDAR sees from each pose;
* :mod:`~map2map.parametric.lidar` - LIDAR error model, thesis eqs. 3.8-3.30;
* :mod:`~map2map.parametric.odometry` - odometry error model, thesis eqs. 3.31-3.53;
* :mod:`~map2map.parametric.additive` - odometry to map error, method of [58],
  thesis eqs. 3.81-3.90;
* :mod:`~map2map.parametric.ekf` - odometry to map error by EKF-SLAM, thesis eqs. 3.54-3.80;
* :mod:`~map2map.parametric.field` - displacement field and the deformed map;
* :mod:`~map2map.parametric.pipeline` - :func:`deform`, the whole model;
* :mod:`~map2map.parametric.figures` - thesis Figs. 3.3 and 5.15.
"""

from .field import DisplacementField, warp_map
from .params import ParametricParams, load_params, save_params
from .pipeline import DeformResult, deform, make_trajectory

__all__ = [
    "DeformResult",
    "DisplacementField",
    "ParametricParams",
    "deform",
    "load_params",
    "make_trajectory",
    "save_params",
    "warp_map",
]
