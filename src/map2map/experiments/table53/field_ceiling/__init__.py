"""How far can moving the SLAM map's walls take Table 5.3's error? (issue #32: the ceiling
of a displacement-field Model_BA, and how much of it the map itself predicts.)"""
