"""Accuracy of the SLAM backends: trajectory and map error, on real logs and in simulation.

Two measurements, one subpackage each:

``slam_accuracy.carmen``
    The two real Radish CARMEN logs (``aces``, ``fhw``) against the raster of their
    corrected poses' scan endpoints (needs ``../shared/data/carmen``).
``slam_accuracy.simulated``
    Simulated 7-minute explorations of procedural apartments and offices against the
    plan and the true trajectory (no data needed).

Run ``python3 -m map2map.experiments.slam_accuracy.carmen ...`` and
``python3 -m map2map.experiments.slam_accuracy.simulated ...``, or
``python3 -m map2map.experiments.slam_accuracy {carmen,simulated} ...``. Current results:
``README.md`` beside this file.
"""
