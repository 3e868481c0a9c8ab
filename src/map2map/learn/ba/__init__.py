"""Model_BA (SLAM -> CAD, thesis 3.1): its config, networks and weights file (``model``),
training (``train``) and ``map2map autocorrect`` with its post-processing."""
