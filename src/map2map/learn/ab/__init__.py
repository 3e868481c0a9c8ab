"""Model_AB (CAD -> SLAM, thesis 3.1, Model_prog): its config and schedule, networks and
weights file (``model``), training (``train``) and ``map2map synthesize`` with its SLAM
rendering, drift and coverage."""
