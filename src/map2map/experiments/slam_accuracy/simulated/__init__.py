"""SLAM quality on simulated explorations against the plan (the script: ``__main__``).

Run ``python3 -m map2map.experiments.slam_accuracy.simulated --help``.
"""
