"""SLAM on the two real CARMEN logs against their corrected poses (the script: ``__main__``).

Run ``python3 -m map2map.experiments.slam_accuracy.carmen --help``.
"""
